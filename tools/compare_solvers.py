#!/usr/bin/env python3
"""Side-by-side solve times of DAQP and quadprog on npz QP files (P, q, G, h).

Usage:
    pip install numpy daqp quadprog
    python3 tools/compare_solvers.py [--repeat K] FILES... > other.csv

Prints CSV `file,solver,status,objective,min_solve_ns` per file and solver:
DAQP's own reported solve time (its `info['solve_time']`, seconds, setup
excluded) and quadprog's wall time around `solve_qp` (it factors the Hessian on
every call, there is no warm setup), minimum over K repeats. Compare with
`ldcbf-sim qp solve --repeat K FILES...` on the same files in the same session.
"""
import argparse
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
    best, res = float("inf"), None
    m = G.shape[0]
    bupper = h.astype(c_double)
    blower = np.full(m, -1e30)
    sense = np.zeros(m, dtype=np.int32)
    for _ in range(repeat):
        x, fval, exitflag, info = daqp.solve(P, q, G, bupper, blower, sense)
        best = min(best, info["solve_time"])
        res = (exitflag, fval)
    status = "solved" if res[0] == 1 else f"exitflag_{res[0]}"
    return status, res[1], int(best * 1e9)


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
    return status, obj, int(best)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=100)
    ap.add_argument("files", nargs="+")
    a = ap.parse_args()
    print("file,solver,status,objective,min_solve_ns")
    for f in a.files:
        P, q, G, h = load(f)
        for name, fn in (("daqp", run_daqp), ("quadprog", run_quadprog)):
            st, obj, ns = fn(P, q, G, h, a.repeat)
            print(f"{f},{name},{st},{obj:.17e},{ns}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
