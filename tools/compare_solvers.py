#!/usr/bin/env python3
"""Side-by-side solve times of DAQP and quadprog on npz QP files (P, q, G, h;
A, b, lb, ub when present).

Usage:
    pip install numpy daqp quadprog
    python3 tools/compare_solvers.py [--repeat K] [--stats S.csv] [--daqp-model] \
        FILES... > other.csv
    ldcbf-sim qp solve --repeat K FILES... > ours.csv
    python3 tools/compare_solvers.py --ours ours.csv --other other.csv
    python3 tools/compare_solvers.py --other other.csv   # DAQP and quadprog only

For example, the n = 50, m = 100 LIP balance set (issue 12), three rounds:
    python3 tools/lip_balance_qps.py /tmp/lipbal
    python3 tools/lip_balance_qps.py --full /tmp/lipbal_full
    for r in 1 2 3; do for s in lipbal lipbal_full; do
      python3 tools/compare_solvers.py --repeat 1000 --daqp-model \
        --stats stats_${s}.csv /tmp/$s/*.npz > other_${s}_$r.csv
    done; done
    python3 tools/compare_solvers.py $(for f in other_*.csv; do echo --other $f; done)

The files are in the qpbenchmark layout (`min 1/2 x'Px + q'x  s.t.  Gx <= h,
Ax = b, lb <= x <= ub`); a key that is missing, a pickled None or empty is
absent. Without A, b, lb, ub (LIPMWALK, the controller's exported QPs) the
solver calls are the same as before they were read. With them, DAQP gets the
bounds as its simple bounds (the first n entries of `bupper`/`blower`), then
the rows of G (upper bound h, no lower bound), then the rows of A as
equalities (`sense` 5, both bounds b); quadprog gets C = [A' -G' I -I],
b = [b -h lb -ub] with `meq` = the rows of A (infinite bounds dropped).
`ldcbf-sim qp solve` reads P, q, G, h only: do not compare it on files with
A, b, lb, ub.

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

`--daqp-model` adds rows `daqp_model`: DAQP's `Model` interface set up once
per file, then per call `update(f=q, bupper, blower, sense)` outside and
`solve()` timed by its `solve_time`. This is the DAQP figure with exactly the
per-G preparation outside: `daqp.solve` returns the unconstrained minimiser
from its setup when it is feasible, so its `solve_time` is then about 16 ns
and the check is in `setup_time` (on LIPBAL's files without an active row:
16 ns against the Model's 1.2 us; on the others both agree).

`--stats S.csv` also writes, per file and solver (`daqp`, `quadprog`, from
the last call), the iterations and the active set at the solution:
`file,solver,status,iterations,active_rows,active_bounds,equalities` (rows of G
and bounds with a nonzero DAQP multiplier, or in quadprog's `iact`; the
equalities are counted apart), and prints to stderr the distribution of the
active-set sizes (rows of G plus bounds) and the DAQP iterations. Both forms
warn on stderr when DAQP and quadprog both solve a file and their objectives
differ by more than 1e-6 relative (`|a - b| > 1e-6 max(1, |a|, |b|)`) or
only one of them solves it.

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
solve time too; with `daqp_model` rows, also our LDP times against them.
With `--other` alone it prints the median times of DAQP (solve, setup+solve,
Model solve) and quadprog per directory.
"""
import argparse
import csv
import os
import statistics
import sys
import time

import numpy as np


def load(path):
    """P, q, G, h, A, b, lb, ub as float arrays, the absent ones None (a
    missing key, a pickled None or an empty array); G, h absent: no rows."""
    d = np.load(path, allow_pickle=True)

    def get(key):
        if key not in d.files:
            return None
        v = d[key]
        if v.dtype == object and v.shape == () and v.item() is None:
            return None
        v = np.asarray(v, dtype=float)
        return None if v.size == 0 else v

    P, q = get("P"), get("q")
    n = q.shape[0]
    G, h = get("G"), get("h")
    if G is None or h is None:
        G, h = np.zeros((0, n)), np.zeros(0)
    return P, q, G, h, get("A"), get("b"), get("lb"), get("ub")


def has_extras(A, b, lb, ub):
    return any(v is not None for v in (A, b, lb, ub))


def daqp_data(P, q, G, h, A, b, lb, ub):
    """Arguments of daqp.solve: (A, bupper, blower, sense), and the index
    ranges of the bounds, the rows of G and the equalities in them."""
    from ctypes import c_double
    n, m = q.shape[0], G.shape[0]
    if not has_extras(A, b, lb, ub):
        # the same call as before A, b, lb, ub were read
        return (G, h.astype(c_double), np.full(m, -1e30), np.zeros(m, dtype=np.int32),
                (0, 0), (0, m), (m, m))
    big = 1e30
    nb = n if (lb is not None or ub is not None) else 0
    me = 0 if A is None else A.shape[0]
    lo = np.full(n, -big) if lb is None else np.maximum(lb, -big)
    hi = np.full(n, big) if ub is None else np.minimum(ub, big)
    rows = np.vstack([G] + ([A] if me else []))
    bupper = np.concatenate(([hi] if nb else []) + [h] + ([b] if me else []))
    blower = np.concatenate(([lo] if nb else []) + [np.full(m, -big)] + ([b] if me else []))
    sense = np.zeros(nb + m + me, dtype=np.int32)
    sense[nb + m:] = 5  # equality
    return (np.ascontiguousarray(rows), bupper.astype(c_double), blower, sense,
            (0, nb), (nb, nb + m), (nb + m, nb + m + me))


def run_daqp(P, q, G, h, A, b, lb, ub, repeat):
    import daqp
    best, best_total, res = float("inf"), float("inf"), None
    rows, bupper, blower, sense, rb, rg, re_ = daqp_data(P, q, G, h, A, b, lb, ub)
    for _ in range(repeat):
        x, fval, exitflag, info = daqp.solve(P, q, rows, bupper, blower, sense)
        best = min(best, info["solve_time"])
        best_total = min(best_total, info["setup_time"] + info["solve_time"])
        res = (exitflag, fval, info)
    status = "solved" if res[0] == 1 else f"exitflag_{res[0]}"
    lam = np.asarray(res[2]["lam"])
    nz = lambda r: int(np.count_nonzero(lam[r[0]:r[1]])) if lam.size else 0
    stats = ("daqp", status, int(res[2]["iterations"]), nz(rg), nz(rb), re_[1] - re_[0])
    return [("daqp", status, res[1], int(round(best * 1e9))),
            ("daqp_total", status, res[1], int(round(best_total * 1e9)))], stats


def run_daqp_model(P, q, G, h, A, b, lb, ub, repeat):
    """DAQP's reusable workspace (`daqp.Model`): set up once per file (P and
    the rows, outside the timing), then per call `update(f=q, bupper, blower,
    sense)` (v = R^-T q and d = b + M v, outside) and `solve()`, timed by its
    `solve_time`. `sense` is passed on every update, which resets the working
    set (a cold start, as in `daqp.solve`). Unlike `daqp.solve`, whose setup
    already returns the unconstrained minimiser when it is feasible (its
    `solve_time` is then about 16 ns), this always times the scan of the
    slacks and the recovery of x: the DAQP figure with exactly the per-G
    preparation outside, for QP families whose G is fixed."""
    import daqp
    rows, bupper, blower, sense, *_ = daqp_data(P, q, G, h, A, b, lb, ub)
    model = daqp.Model()
    model.setup(P, q, rows, bupper, blower, sense)
    best, res = float("inf"), None
    for _ in range(repeat):
        model.update(f=q, bupper=bupper, blower=blower, sense=sense)
        x, fval, exitflag, info = model.solve()
        best = min(best, info["solve_time"])
        res = (exitflag, fval)
    status = "solved" if res[0] == 1 else f"exitflag_{res[0]}"
    return [("daqp_model", status, res[1], int(round(best * 1e9)))]


def quadprog_data(P, q, G, h, A, b, lb, ub):
    """(C, b, meq) of quadprog.solve_qp (C'x >= b, the first meq equalities)
    and the kinds of the columns of C ('e', 'g', 'b')."""
    n = q.shape[0]
    if not has_extras(A, b, lb, ub):
        # the same call as before A, b, lb, ub were read
        return -G.T, -h, 0, ["g"] * G.shape[0]
    cols, rhs, kinds = [], [], []
    me = 0 if A is None else A.shape[0]
    if me:
        cols.append(A.T); rhs.append(b); kinds += ["e"] * me
    cols.append(-G.T); rhs.append(-h); kinds += ["g"] * G.shape[0]
    eye = np.eye(n)
    for bound, sign in ((lb, 1.0), (ub, -1.0)):
        if bound is not None:
            keep = np.isfinite(bound)
            cols.append(sign * eye[:, keep]); rhs.append(sign * bound[keep])
            kinds += ["b"] * int(keep.sum())
    return np.ascontiguousarray(np.hstack(cols)), np.concatenate(rhs), me, kinds


def run_quadprog(P, q, G, h, A, b, lb, ub, repeat):
    import quadprog
    C, rhs, meq, kinds = quadprog_data(P, q, G, h, A, b, lb, ub)
    best, status, obj, out = float("inf"), "solved", float("nan"), None
    for _ in range(repeat):
        t0 = time.perf_counter_ns()
        try:
            # quadprog: min 1/2 x'Gx - a'x s.t. C'x >= b
            out = quadprog.solve_qp(P, -q, C, rhs, meq)
            obj = out[1]
        except ValueError as e:
            status = "infeasible" if "constraints are inconsistent" in str(e) else "error"
        best = min(best, time.perf_counter_ns() - t0)
    if status == "solved" and out is not None:
        iact = [kinds[i - 1] for i in out[5]]
        stats = ("quadprog", status, int(out[3][0]), iact.count("g"), iact.count("b"),
                 meq)
    else:
        stats = ("quadprog", status, 0, 0, 0, meq)
    return [("quadprog", status, obj, int(best))], stats


def objectives_agree(a, b):
    return abs(a - b) <= 1e-6 * max(1.0, abs(a), abs(b))


def check_daqp_quadprog(f, row_a, row_b):
    """Warn (stderr) when two solvers' rows (name, status, objective, ns),
    DAQP's and quadprog's, disagree on status or objective; True if they
    agree."""
    (n1, s1, o1, _), (n2, s2, o2, _) = row_a, row_b
    if (s1 == "solved") != (s2 == "solved"):
        print(f"warning: {f}: {n1} {s1}, {n2} {s2}", file=sys.stderr)
        return False
    if s1 == "solved" and not objectives_agree(float(o1), float(o2)):
        print(f"warning: objectives differ on {f} ({n1} vs {n2}): {o1} vs {o2}",
              file=sys.stderr)
        return False
    return True


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
    if any(solver == "daqp_model" for _, solver in other):
        # only with `--daqp-model` runs: the fixed-G figures against DAQP's Model
        print()
        print("Against DAQP's Model interface (set up once, q and h updated outside "
              "its solve time), per-file ratio, median and worst (largest):")
        print()
        print("| set | DAQP Model solve ns (median) | ours LDP / DAQP Model solve "
              "| ours LDP + load / DAQP Model solve |")
        print("|---|---|---|---|")
        for s in sorted(times):
            cells = []
            for col in ("min_ldp_ns", "ldp_with_load_ns"):
                v = [int(o[col]) / max(1, int(other[(o["file"], "daqp_model")]["min_solve_ns"]))
                     for o in times[s] if (o["file"], "daqp_model") in other]
                cells.append(f"{statistics.median(v):.2f} (worst {max(v):.2f})" if v else "-")
            print(f"| {s} | {med(other_times.get((s, 'daqp_model'), []))} | "
                  + " | ".join(cells) + " |")
    return 0


def summary_other(other_csvs):
    """DAQP and quadprog alone: median times per directory (per-file minimum
    over the runs) and the DAQP/quadprog agreement."""
    other = per_file_min(other_csvs, ["file", "solver"], ["min_solve_ns"])
    files = sorted({f for f, _ in other})
    row = lambda f, v: (v, other[(f, v)]["status"], other[(f, v)]["objective"], 0)
    bad = 0
    for f in files:
        if (f, "quadprog") not in other:
            continue
        ok = True
        for v in ("daqp", "daqp_model"):
            if (f, v) in other:
                ok = check_daqp_quadprog(f, row(f, v), row(f, "quadprog")) and ok
        bad += not ok
    sets = {}
    for f in files:
        sets.setdefault(os.path.basename(os.path.dirname(f)) or ".", []).append(f)
    print("| set | files | solved (DAQP, quadprog) | DAQP solve ns (median) "
          "| DAQP setup+solve ns (median) | DAQP Model solve ns (median) "
          "| quadprog ns (median) |")
    print("|---|---|---|---|---|---|---|")
    for s in sorted(sets):
        def col(solver, field="min_solve_ns"):
            return [other[(f, solver)][field] for f in sets[s] if (f, solver) in other]
        med = lambda v: f"{statistics.median(int(x) for x in v):.0f}" if v else "-"
        solved = [sum(st == "solved" for st in col(v, "status")) for v in ("daqp", "quadprog")]
        print(f"| {s} | {len(sets[s])} | {solved[0]}, {solved[1]} | {med(col('daqp'))} | "
              f"{med(col('daqp_total'))} | {med(col('daqp_model'))} | "
              f"{med(col('quadprog'))} |")
    print(f"\nDAQP and quadprog: {bad} files with a different status or objective "
          "(1e-6 relative)", file=sys.stderr)
    return 0


def print_stats(stats):
    """Distribution of the active-set sizes (rows of G plus bounds) and of
    DAQP's iterations, to stderr."""
    from collections import Counter
    for solver in ("daqp", "quadprog"):
        rows = [r for r in stats if r[1] == solver and r[2] == "solved"]
        if not rows:
            continue
        act = [r[4] + r[5] for r in rows]
        dist = sorted(Counter(act).items())
        print(f"{solver}: {len(rows)} solved, {sum(a > 0 for a in act)} with active "
              f"inequalities (rows of G or bounds), {sum(r[5] > 0 for r in rows)} with "
              f"active bounds; active-set size (size: files) "
              + ", ".join(f"{k}: {v}" for k, v in dist), file=sys.stderr)
        its = [r[3] for r in rows]
        print(f"{solver} iterations: median {statistics.median(its):g}, max {max(its)}; "
              + ", ".join(f"{k}: {v}" for k, v in sorted(Counter(its).items())),
              file=sys.stderr)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=100)
    ap.add_argument("--ours", action="append", default=[], metavar="CSV",
                    help="summary mode: output of `ldcbf-sim qp solve` (repeatable: "
                    "per-file minimum over the runs)")
    ap.add_argument("--other", action="append", default=[], metavar="CSV",
                    help="summary mode: output of this script (repeatable)")
    ap.add_argument("--daqp-model", action="store_true",
                    help="also time DAQP's Model interface (rows `daqp_model`: set up "
                    "once, q and h updated outside the timing)")
    ap.add_argument("--stats", metavar="CSV",
                    help="also write iterations and active sets per file and solver")
    ap.add_argument("files", nargs="*")
    a = ap.parse_args()
    if a.ours or a.other:
        if not a.other:
            ap.error("--ours needs --other")
        if not a.ours:
            return summary_other(a.other)
        return summary(a.ours, a.other)
    if not a.files:
        ap.error("no files")
    print("file,solver,status,objective,min_solve_ns")
    stats, bad = [], 0
    for f in a.files:
        P, q, G, h, A, b, lb, ub = load(f)
        rows = []
        for fn in (run_daqp, run_quadprog):
            out, info = fn(P, q, G, h, A, b, lb, ub, a.repeat)
            stats.append((f,) + info)
            for name, st, obj, ns in out:
                rows.append((name, st, obj, ns))
                print(f"{f},{name},{st},{obj:.17e},{ns}")
        ok = check_daqp_quadprog(f, rows[0], rows[2])
        if a.daqp_model:
            for name, st, obj, ns in run_daqp_model(P, q, G, h, A, b, lb, ub, a.repeat):
                print(f"{f},{name},{st},{obj:.17e},{ns}")
                ok = check_daqp_quadprog(f, (name, st, obj, ns), rows[2]) and ok
        bad += not ok
    print(f"DAQP{' (both interfaces)' if a.daqp_model else ''} and quadprog: {bad} of "
          f"{len(a.files)} files with a different status or objective (1e-6 relative)",
          file=sys.stderr)
    if a.stats:
        with open(a.stats, "w") as out:
            out.write("file,solver,status,iterations,active_rows,active_bounds,equalities\n")
            for r in stats:
                out.write(",".join(str(x) for x in r) + "\n")
        print_stats(stats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
