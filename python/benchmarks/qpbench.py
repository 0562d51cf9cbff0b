#!/usr/bin/env python3
"""qpbenchmark's own harness on the repository's dense MPC test sets, with
ldcbf beside the solvers that install from PyPI.

Usage (after ``pip install ./python qpbenchmark quadprog daqp proxsuite piqp
clarabel osqp``):

    # our controller's QPs: every cycle QP of closed-loop runs, exported
    python3 python/benchmarks/qpbench.py --export /tmp/ctlqp paper maze --every 4
    # the harness on LIPMWALK and on them, five runs, the tables in Markdown
    python3 python/benchmarks/qpbench.py --runs 5 tests/data/lipmwalk /tmp/ctlqp

Each positional argument is a directory of npz files in the layout
qpbenchmark's ``Problem.load`` reads (keys P, q, G, h and optionally A, b, lb,
ub; ``tests/data/lipmwalk`` and ``ldcbf-sim run --export-qps`` write it): one
test set. The harness is qpbenchmark's (``qpbenchmark.run``: every problem,
every solver, every settings, timed around ``qpsolvers.solve_problem``; its
tolerances and its per-solver settings for ``default``, ``high_accuracy``,
``low_accuracy`` and ``mid_accuracy``). ldcbf is not in qpbenchmark's list of
solvers with known settings: it is added to it here and runs with its
defaults in every settings (primal tolerance 1e-10 on unit rows; the active
set makes the answer exact to rounding, so no tolerance is loosened for the
low-accuracy settings).

Printed per set: success rate (%) and runtime shifted geometric mean (shift
10 s, relative to the best solver of the settings; a failure counts as the
10 s time limit), as qpbenchmark's report computes them, for each run and
settings; with ``--runs N > 1`` also the tables of the N runs combined, each
(problem, solver, settings) at its fastest run (the shared development
machine preempts single calls for milliseconds, against calls of tens of
microseconds, and the shifted mean with a 10 s shift is close to an
arithmetic mean). ``--report DIR`` also writes qpbenchmark's full report of the last
run (``DIR/<set>.md``) and its results CSV.

``--export DIR SCENARIO...`` writes the QPs of ``ldcbf-sim run SCENARIO
--export-qps`` (every ``--every``-th cycle, as ``<scenario>_<k>.npz`` with the
absent members A, b, lb, ub stored as None, as in the LIPMWALK files: the
export holds P, q, G, h only, and qpsolvers' ``Problem.load`` needs every key)
into DIR and exits; the CLI is ``$LDCBF_SIM`` or ``cargo run --release -p
ldcbf-sim``.

Python's garbage collector is off while the harness runs (a collection
pauses whichever solver call triggers it, a millisecond against calls of tens
of microseconds).
"""

import argparse
import gc
import os
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "tools"))
from lip_balance_qps import write_npz  # noqa: E402  (the npz writer of the sets)

#: The solvers of the comparison (qpsolvers names); those not installed are
#: left out with a note.
SOLVERS = ["ldcbf", "quadprog", "daqp", "proxqp", "piqp", "clarabel", "osqp"]


def export(out, scenarios, every):
    """Writes every `every`-th cycle QP of each scenario's run into `out`."""
    cli = shlex.split(os.environ.get("LDCBF_SIM", "")) or [
        "cargo", "run", "--release", "--locked", "-q", "-p", "ldcbf-sim", "--",
    ]
    out = Path(out)
    if out.exists():
        sys.exit(f"error: --export {out}: exists; give a new directory")
    out.mkdir(parents=True)
    with tempfile.TemporaryDirectory() as tmp:
        for sc in scenarios:
            qdir = Path(tmp) / f"qps_{sc}"
            cmd = cli + [
                "run", sc, "--out", str(Path(tmp) / f"out_{sc}"), "--no-plots",
                "--export-qps", str(qdir),
            ]
            p = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
            if p.returncode != 0:
                sys.exit(f"error: {' '.join(cmd)}:\n{p.stderr}")
            files = sorted(qdir.glob("*.npz"))
            for k, f in enumerate(files[::every]):
                # The export holds P, q, G, h only; qpsolvers' Problem.load
                # wants every key, the absent ones as None (LIPMWALK's bytes).
                with np.load(f) as d:
                    arrays = {key: d[key] for key in "PqGh"}
                arrays.update(A=None, b=None, lb=None, ub=None)
                write_npz(out / f"{sc}_{k}.npz", arrays)
            print(f"{sc}: {len(files[::every])} of {len(files)} cycle QPs -> {out}")


def make_test_set(folder, solvers, limit):
    """A qpbenchmark test set of the npz files of `folder`."""
    import qpbenchmark
    from qpbenchmark.solver_settings import SolverSettings

    import ldcbf_nav  # noqa: F401  (registers "ldcbf" with qpsolvers)

    SolverSettings.IMPLEMENTED_SOLVERS.add("ldcbf")
    files = sorted(Path(folder).glob("*.npz"), key=lambda f: (len(f.name), f.name))
    if not files:
        sys.exit(f"error: {folder}: no .npz files")
    files = files[:limit] if limit else files

    class DenseMpcSet(qpbenchmark.TestSet):
        """The npz files of one folder."""

        @property
        def description(self):
            return f"Dense MPC QPs of {folder} ({len(files)} problems)."

        @property
        def title(self):
            return f"ldcbf-nav dense MPC test set: {Path(folder).name}"

        @property
        def sparse_only(self):
            return False

        def __iter__(self):
            for f in files:
                yield qpbenchmark.Problem.load(str(f))

    ts = DenseMpcSet()
    missing = [s for s in solvers if s not in ts.solvers]
    if missing:
        print(f"note: not installed, left out: {', '.join(missing)}")
    ts.solvers = set(s for s in solvers if s in ts.solvers)
    return ts


def tables(ts, results):
    """Success rate and runtime shifted geometric mean, per solver and settings."""
    tol = ts.tolerances
    success = results.build_success_rate_df(
        {k: t.primal for k, t in tol.items()},
        {k: t.dual for k, t in tol.items()},
        {k: t.gap for k, t in tol.items()},
    )
    runtime = results.build_shgeom_df(
        metric="runtime",
        shift=10.0,
        not_found_values={k: t.runtime for k, t in tol.items()},
    )
    return success, runtime


def print_tables(title, ts, results, worst, name):
    """Prints the success / runtime table of `results`; keeps ldcbf's worst."""
    success, runtime = tables(ts, results)
    print(f"{title}: success rate (%) / runtime shifted geometric mean\n")
    settings = list(success.columns)
    print("| solver | " + " | ".join(settings) + " |")
    print("|---" * (len(settings) + 1) + "|")
    for s in sorted(success.index, key=lambda s: runtime.loc[s].mean()):
        cells = [f"{success.loc[s, c]:.0f} / {runtime.loc[s, c]:.2f}" for c in settings]
        print(f"| {s} | " + " | ".join(cells) + " |")
    print()
    if "ldcbf" in success.index:
        w = worst.setdefault(name, [100.0, 0.0])
        w[0] = min(w[0], success.loc["ldcbf"].min())
        w[1] = max(w[1], runtime.loc["ldcbf"].max())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("sets", nargs="*", help="directories of npz files")
    ap.add_argument("--runs", type=int, default=1, help="harness runs per set")
    ap.add_argument("--limit", type=int, default=0, help="first N files of each set")
    ap.add_argument(
        "--solvers",
        type=lambda v: v.split(","),
        default=SOLVERS,
        help="comma-separated qpsolvers names (default: %(default)s)",
    )
    ap.add_argument("--report", help="directory for qpbenchmark's report and CSV")
    ap.add_argument("--export", help="write controller QPs here (see docs)")
    ap.add_argument("--every", type=int, default=1)
    ap.add_argument(
        "--require-success",
        action="store_true",
        help="exit 1 unless ldcbf has 100 %% success in every settings",
    )
    args = ap.parse_args()
    if args.export:
        export(args.export, args.sets, args.every)
        return
    if not args.sets:
        ap.error("no test set given")
    import qpbenchmark
    from qpbenchmark.report import Report

    worst = {}
    scratch = tempfile.TemporaryDirectory()
    for folder in args.sets:
        ts = make_test_set(folder, args.solvers, args.limit)
        name = Path(folder).name
        print(f"\n### {name}: {ts.count_problems()} problems, {args.runs} run(s)\n")
        frames = []
        for r in range(args.runs):
            # A new CSV per run: the harness skips problems a results file
            # already holds.
            csv = Path(scratch.name) / f"{name}_{r}.csv"
            results = qpbenchmark.Results(csv, ts)
            # Python's garbage collector off during the harness (on for the
            # tables): its pauses land in whichever solver call triggers them.
            gc.disable()
            try:
                qpbenchmark.run(ts, results)
            finally:
                gc.enable()
            frames.append(results.df)
            print_tables(f"run {r + 1}", ts, results, worst, name)
        if args.runs > 1:
            # Each (problem, solver, settings) at its fastest run: a
            # preemption of the shared machine lands in one run, not in all.
            import pandas

            df = pandas.concat(frames, ignore_index=True)
            best = df.loc[df.groupby(["problem", "solver", "settings"])["runtime"].idxmin()]
            results.df = best.reset_index(drop=True)
            print_tables(f"best of {args.runs} runs", ts, results, worst, name)
        if args.report:
            out = Path(args.report)
            out.mkdir(parents=True, exist_ok=True)
            results.write(out / f"{name}.csv")
            Report("ldcbf-nav", results).write(str(out / f"{name}.md"))
    for name, (succ, rt) in worst.items():
        print(f"ldcbf on {name}: lowest success {succ:.0f} %, highest runtime shm {rt:.2f}")
    if args.require_success:
        failed = [name for name, (succ, _) in worst.items() if succ < 100.0]
        if len(worst) != len(args.sets) or failed:
            sys.exit(f"error: ldcbf below 100 % success (or not run) on: {failed or args.sets}")


if __name__ == "__main__":
    main()
