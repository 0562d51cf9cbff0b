#!/usr/bin/env python3
"""Side-by-side solve times of DAQP and quadprog on npz QP files (P, q, G, h).

Usage:
    pip install numpy daqp quadprog
    python3 tools/compare_solvers.py [--repeat K] FILES... > other.csv
    ldcbf-sim qp solve --repeat K FILES... > ours.csv
    python3 tools/compare_solvers.py --summary ours.csv other.csv

The first form prints CSV `file,solver,status,objective,min_solve_ns` per file
and solver, minimum over K repeats:

* `daqp`: DAQP's own reported solve time (`info['solve_time']`). It excludes
  DAQP's setup (Cholesky of P and the transform of every row, M = G R^-1),
  which a controller whose G changes every cycle pays every cycle.
* `daqp_total`: `info['setup_time'] + info['solve_time']` of the same call:
  the like-for-like figure against `ldcbf-sim qp solve`, whose time includes
  everything it does with the rows (only the factorisation of the constant
  Hessian is outside, as in the controller).
* `quadprog`: wall time around `solve_qp` (it factors the Hessian on every
  call and has no separate setup; the time includes the Python call overhead).

The `--summary` form joins the two CSVs on the file column and prints, per
directory of the files, the median and the worst (largest) per-file ratio of
our time to each other solver's time, as a Markdown table.
"""
import argparse
import csv
import os
import statistics
import sys
import time

import numpy as np


def load(path):
    d = np.load(path, allow_pickle=True)
    return (np.asarray(d["P"], dtype=float), np.asarray(d["q"], dtype=float),
            np.asarray(d["G"], dtype=float), np.asarray(d["h"], dtype=float))


def run_daqp(P, q, G, h, repeat):
    import daqp
    from ctypes import c_double
    best, best_total, res = float("inf"), float("inf"), None
    m = G.shape[0]
    bupper = h.astype(c_double)
    blower = np.full(m, -1e30)
    sense = np.zeros(m, dtype=np.int32)
    for _ in range(repeat):
        x, fval, exitflag, info = daqp.solve(P, q, G, bupper, blower, sense)
        best = min(best, info["solve_time"])
        best_total = min(best_total, info["setup_time"] + info["solve_time"])
        res = (exitflag, fval)
    status = "solved" if res[0] == 1 else f"exitflag_{res[0]}"
    return [("daqp", status, res[1], int(round(best * 1e9))),
            ("daqp_total", status, res[1], int(round(best_total * 1e9)))]


def run_quadprog(P, q, G, h, repeat):
    import quadprog
    best, status, obj = float("inf"), "solved", float("nan")
    for _ in range(repeat):
        t0 = time.perf_counter_ns()
        try:
            # quadprog: min 1/2 x'Gx - a'x s.t. C'x >= b
            x, f, *_ = quadprog.solve_qp(P, -q, -G.T, -h, 0)
            obj = f
        except ValueError as e:
            status = "infeasible" if "constraints are inconsistent" in str(e) else "error"
        best = min(best, time.perf_counter_ns() - t0)
    return [("quadprog", status, obj, int(best))]


def summary(ours_csv, other_csv):
    ours = {r["file"]: r for r in csv.DictReader(open(ours_csv))}
    ratios = {}  # (set, solver) -> [ratio]
    sets = {}
    for r in csv.DictReader(open(other_csv)):
        o = ours.get(r["file"])
        if o is None:
            continue
        s = os.path.basename(os.path.dirname(r["file"])) or "."
        sets.setdefault(s, set()).add(r["file"])
        if o["status"] == "solved" and r["status"] == "solved":
            a, b = float(o["objective"]), float(r["objective"])
            if abs(a - b) > 1e-6 * max(1.0, abs(a), abs(b)):
                print(f"warning: objectives differ on {r['file']}: {a} vs {b}",
                      file=sys.stderr)
        ratios.setdefault((s, r["solver"]), []).append(
            int(o["min_solve_ns"]) / max(1, int(r["min_solve_ns"])))
    times = {}
    for f, o in ours.items():
        s = os.path.basename(os.path.dirname(f)) or "."
        times.setdefault(s, []).append(int(o["min_solve_ns"]))
    print("| set | files | ours median ns | ours/DAQP solve: median, worst "
          "| ours/DAQP setup+solve: median, worst | ours/quadprog: median, worst |")
    print("|---|---|---|---|---|---|")
    for s in sorted(sets):
        cells = []
        for solver in ("daqp", "daqp_total", "quadprog"):
            v = ratios.get((s, solver), [])
            cells.append(f"{statistics.median(v):.2f}, {max(v):.2f}" if v else "-")
        print(f"| {s} | {len(sets[s])} | {statistics.median(times[s]):.0f} | "
              + " | ".join(cells) + " |")
    return 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=100)
    ap.add_argument("--summary", nargs=2, metavar=("OURS_CSV", "OTHER_CSV"))
    ap.add_argument("files", nargs="*")
    a = ap.parse_args()
    if a.summary:
        return summary(*a.summary)
    print("file,solver,status,objective,min_solve_ns")
    for f in a.files:
        P, q, G, h = load(f)
        for fn in (run_daqp, run_quadprog):
            for name, st, obj, ns in fn(P, q, G, h, a.repeat):
                print(f"{f},{name},{st},{obj:.17e},{ns}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
