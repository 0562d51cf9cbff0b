#!/usr/bin/env python3
"""Per-call time of the QP solver from Python against DAQP's binding.

Usage (after ``pip install ./python daqp``):

    python3 tools/lip_balance_qps.py /tmp/lipbal          # n = 50, m = 100
    python3 python/benchmarks/per_call.py tests/data/lipmwalk /tmp/lipbal

For each set (a directory of qpbenchmark npz files with P, q, G, h), every
file is solved by each contender in turn, file by file, for ``--rounds``
rounds (interleaved: one round visits every file and every contender), and
the wall time of each call is taken with ``time.perf_counter_ns``. Printed
per set and contender: the median over the files of the per-file median
time (us), the same with the per-file minimum (less sensitive to a loaded
machine), and their ratios to DAQP's (cold, ``daqp.solve``). Contenders:

* ``daqp.solve``: DAQP's Python binding, one cold call (setup + solve);
  ``blower`` and ``sense`` built once per file outside the timing.
* ``solve_qp``: ``ldcbf_nav.solve_qp`` (the dict interface).
* ``solve_dense``: ``ldcbf_nav.solve_dense``, one cold call (factor of ``P``
  and everything else inside).
* ``QpSolver, cold``: ``QpSolver(P)`` made once per set (every file of a set
  has the same ``P``; checked), then ``solve(q, G, h, warm_start=False)``.
* ``QpSolver, warm``: the same object, ``warm_start=True``, files solved in
  order (file k starts from the active set of file k - 1, as in an MPC loop);
  the first file of a round starts from the last file of the previous round.

Every contender's objective is checked against DAQP's (relative 1e-6).
"""

import argparse
import statistics
import sys
import time
from ctypes import c_int
from pathlib import Path

import numpy as np


def load(folder):
    """The (name, P, q, G, h) of every npz file of a folder, sorted by name."""
    files = sorted(Path(folder).glob("*.npz"), key=lambda f: (len(f.name), f.name))
    if not files:
        sys.exit(f"error: {folder}: no .npz files")
    out = []
    for f in files:
        d = np.load(f, allow_pickle=True)
        out.append(
            (
                f.name,
                *(np.ascontiguousarray(d[k], dtype=np.float64) for k in "PqGh"),
            )
        )
    return out


def run_set(name, problems, rounds):
    """Times every contender on one set; prints one line each."""
    import daqp

    import ldcbf_nav

    P0 = problems[0][1]
    same_p = all(np.array_equal(p[1], P0) for p in problems)
    solver = ldcbf_nav.QpSolver(P0) if same_p else None
    prepared = []
    for fname, P, q, G, h in problems:
        blower = np.full(h.size, -1e30)
        sense = np.zeros(h.size, dtype=c_int)
        prepared.append((fname, P, q, G, h, blower, sense))

    def c_daqp(P, q, G, h, bl, se):
        x, obj, flag, _ = daqp.solve(P, q, G, h, bl, se)
        return obj if flag > 0 else None

    def c_solve_qp(P, q, G, h, bl, se):
        r = ldcbf_nav.solve_qp(P, q, G, h)
        return r["objective"] if r["status"] == "solved" else None

    def c_dense(P, q, G, h, bl, se):
        r = ldcbf_nav.solve_dense(P, q, G, h)
        return r[5] if r[0] == "solved" else None

    def c_cold(P, q, G, h, bl, se):
        r = solver.solve(q, G, h, warm_start=False)
        return r[5] if r[0] == "solved" else None

    def c_warm(P, q, G, h, bl, se):
        r = solver.solve(q, G, h, warm_start=True)
        return r[5] if r[0] == "solved" else None

    contenders = [
        ("daqp.solve", c_daqp),
        ("solve_qp", c_solve_qp),
        ("solve_dense", c_dense),
    ]
    if solver is not None:
        contenders += [("QpSolver, cold", c_cold), ("QpSolver, warm", c_warm)]
    times = {c: [[] for _ in prepared] for c, _ in contenders}
    ref = [c_daqp(*p[1:]) for p in prepared]
    clock = time.perf_counter_ns
    for _ in range(rounds):
        for k, p in enumerate(prepared):
            args = p[1:]
            for cname, fn in contenders:
                t0 = clock()
                obj = fn(*args)
                t1 = clock()
                times[cname][k].append(t1 - t0)
                if obj is None or abs(obj - ref[k]) > 1e-6 * max(1.0, abs(ref[k])):
                    sys.exit(f"error: {name}/{p[0]}: {cname} gives {obj}, DAQP {ref[k]}")
    med = {
        c: statistics.median(statistics.median(t) for t in times[c]) / 1000.0
        for c in times
    }
    low = {c: statistics.median(min(t) for t in times[c]) / 1000.0 for c in times}
    n, m = problems[0][1].shape[0], problems[0][3].shape[0]
    print(f"\n{name}: {len(problems)} files, n = {n}, m = {m}, {rounds} rounds")
    print("| contender | per call, median (us) | / DAQP | per call, minimum (us) | / DAQP |")
    print("|---|---|---|---|---|")
    d, dl = med["daqp.solve"], low["daqp.solve"]
    for c in times:
        print(f"| {c} | {med[c]:.1f} | {med[c] / d:.2f} | {low[c]:.1f} | {low[c] / dl:.2f} |")
    if solver is not None:
        print(f"(QpSolver path: {solver.path})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sets", nargs="+", help="directories of npz files")
    ap.add_argument("--rounds", type=int, default=20)
    args = ap.parse_args()
    for s in args.sets:
        run_set(Path(s).name, load(s), args.rounds)


if __name__ == "__main__":
    main()
