#!/usr/bin/env python3
"""Side-by-side solve times of DAQP and quadprog on npz QP files (P, q, G, h).

Usage:
    pip install numpy daqp quadprog
    python3 tools/compare_solvers.py [--repeat K] FILES... > other.csv
    ldcbf-sim qp solve --repeat K FILES... > ours.csv
    python3 tools/compare_solvers.py --ours ours.csv --other other.csv

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

The summary form joins the CSVs on the file column (each of `--ours` and
`--other` may be repeated: per-file minimum over the runs) and prints, per
directory of the files, median times and the median and worst (largest)
per-file ratio of our time to each other solver's, as Markdown tables. Our
`min_prepared_ns` (row norms prepared outside the timing, for a fixed G) is
compared with DAQP's solve time only, and so is `min_ldp_ns` (the
least-distance path for a fixed G: M = G L^-T and its Gram matrix prepared
once, v = L^-1 q and the slacks at the unconstrained minimiser loaded per
(q, h), both outside the timing, the same split as DAQP's setup/solve);
`min_ldp_ns + min_ldp_load_ns` (the load included) is shown against DAQP's
solve time too.
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


def per_file_min(paths, key_fields, value_fields):
    """Rows of several CSV runs keyed by `key_fields`, each value the minimum
    over the runs; the other fields from the first run."""
    out = {}
    for p in paths:
        for r in csv.DictReader(open(p)):
            k = tuple(r[f] for f in key_fields)
            if k not in out:
                out[k] = dict(r)
            else:
                for f in value_fields:
                    out[k][f] = str(min(int(out[k][f]), int(r[f])))
    return out


def summary(ours_csvs, other_csvs):
    ours = per_file_min(ours_csvs, ["file"],
                        ["min_solve_ns", "min_prepared_ns", "min_ldp_ns", "min_ldp_load_ns"])
    for o in ours.values():
        o["ldp_with_load_ns"] = str(int(o["min_ldp_ns"]) + int(o["min_ldp_load_ns"]))
    other = per_file_min(other_csvs, ["file", "solver"], ["min_solve_ns"])
    # (set, label) -> per-file ratios; label: (ours column, other solver)
    pairs = [("min_solve_ns", "daqp"), ("min_solve_ns", "daqp_total"),
             ("min_prepared_ns", "daqp"), ("min_ldp_ns", "daqp"),
             ("ldp_with_load_ns", "daqp"), ("min_solve_ns", "quadprog")]
    ratios, times, mism = {}, {}, 0
    for (f,), o in ours.items():
        s = os.path.basename(os.path.dirname(f)) or "."
        times.setdefault(s, []).append(o)
        for col, solver in pairs:
            r = other.get((f, solver))
            if r is None:
                continue
            if solver == "daqp" and col == "min_solve_ns" and (
                    o["status"] == "solved") != (r["status"] == "solved"):
                mism += 1
            ratios.setdefault((s, col, solver), []).append(
                int(o[col]) / max(1, int(r["min_solve_ns"])))
            if o["status"] == "solved" and r["status"] == "solved":
                a, b = float(o["objective"]), float(r["objective"])
                if abs(a - b) > 1e-6 * max(1.0, abs(a), abs(b)):
                    print(f"warning: objectives differ on {f} ({solver}): {a} vs {b}",
                          file=sys.stderr)
    if mism:
        print(f"warning: {mism} files solved by one of ours/DAQP only", file=sys.stderr)
    print("| set | files | ours ns (median) | ours prepared ns (median) "
          "| ours LDP ns (median) | ours LDP load ns (median) "
          "| DAQP solve ns (median) | DAQP setup+solve ns (median) | quadprog ns (median) |")
    print("|---|---|---|---|---|---|---|---|---|")
    other_times = {}  # (set, solver) -> [ns]
    for (f, solver), r in other.items():
        s = os.path.basename(os.path.dirname(f)) or "."
        other_times.setdefault((s, solver), []).append(int(r["min_solve_ns"]))

    def med(values):
        return f"{statistics.median(values):.0f}" if values else "-"

    for s in sorted(times):
        print(f"| {s} | {len(times[s])} | "
              f"{med([int(o['min_solve_ns']) for o in times[s]])} | "
              f"{med([int(o['min_prepared_ns']) for o in times[s]])} | "
              f"{med([int(o['min_ldp_ns']) for o in times[s]])} | "
              f"{med([int(o['min_ldp_load_ns']) for o in times[s]])} | "
              + " | ".join(med(other_times.get((s, v), []))
                           for v in ("daqp", "daqp_total", "quadprog")) + " |")
    print()
    print("Per-file ratio of times (ours / other), median and worst (largest):")
    print()
    print("| set | ours / DAQP setup+solve | ours / DAQP solve "
          "| ours prepared / DAQP solve | ours LDP / DAQP solve "
          "| ours LDP + load / DAQP solve | ours / quadprog |")
    print("|---|---|---|---|---|---|---|")
    for s in sorted(times):
        cells = []
        for key in [("min_solve_ns", "daqp_total"), ("min_solve_ns", "daqp"),
                    ("min_prepared_ns", "daqp"), ("min_ldp_ns", "daqp"),
                    ("ldp_with_load_ns", "daqp"), ("min_solve_ns", "quadprog")]:
            v = ratios.get((s,) + key, [])
            cells.append(f"{statistics.median(v):.2f} (worst {max(v):.2f})" if v else "-")
        print(f"| {s} | " + " | ".join(cells) + " |")
    return 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=100)
    ap.add_argument("--ours", action="append", default=[], metavar="CSV",
                    help="summary mode: output of `ldcbf-sim qp solve` (repeatable: "
                    "per-file minimum over the runs)")
    ap.add_argument("--other", action="append", default=[], metavar="CSV",
                    help="summary mode: output of this script (repeatable)")
    ap.add_argument("files", nargs="*")
    a = ap.parse_args()
    if a.ours or a.other:
        if not (a.ours and a.other):
            ap.error("--ours and --other go together")
        return summary(a.ours, a.other)
    if not a.files:
        ap.error("no files")
    print("file,solver,status,objective,min_solve_ns")
    for f in a.files:
        P, q, G, h = load(f)
        for fn in (run_daqp, run_quadprog):
            for name, st, obj, ns in fn(P, q, G, h, a.repeat):
                print(f"{f},{name},{st},{obj:.17e},{ns}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
