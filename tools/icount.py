#!/usr/bin/env python3
"""Instruction-count guard of the solver and the controller's step.

Builds `benches/icount.rs` (release profile, no target-cpu flags), runs each
of its workloads once under valgrind's callgrind, counting only the function
`icount::counted` (the measured part; inputs are prepared outside it) and only
the instructions of the icount binary itself (not the C library's, whose
`memcpy`/`malloc` variants depend on the CPU and the distribution), and
compares the counts with the committed baseline `benches/icount-baseline.txt`.

Exit status 1 when a count grew by more than the tolerance (default 3 %).
A deliberate change of a count (a faster solver, or a slower one for a good
reason) is recorded with `--update` and committed with the reason in the
commit message.

Usage (from the workspace root):

    python3 tools/icount.py                      # build, count, compare
    python3 tools/icount.py --update             # write the baseline
    python3 tools/icount.py --lipmwalk DIR       # another LIPMWALK folder
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BASELINE = os.path.join(ROOT, "benches", "icount-baseline.txt")
LIPMWALK = os.path.join(ROOT, "tests", "data", "lipmwalk")


def build():
    """Builds the icount bench binary; returns its path."""
    env = dict(os.environ)
    # The counts are the binary's: no flags from the environment.
    for k in ("RUSTFLAGS", "CARGO_ENCODED_RUSTFLAGS", "CARGO_BUILD_RUSTFLAGS"):
        env.pop(k, None)
    out = subprocess.run(
        ["cargo", "build", "--release", "--locked", "--bench", "icount",
         "--message-format=json-render-diagnostics"],
        cwd=ROOT, env=env, check=True, stdout=subprocess.PIPE, text=True).stdout
    exe = None
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg["target"]["name"] == "icount":
            exe = msg.get("executable") or exe
    if exe is None:
        sys.exit("icount.py: cargo did not report the icount executable")
    return exe


def own_instructions(path, binary):
    """Instructions (Ir) executed in `binary`'s own code, summed over the
    functions of a callgrind output written with --compress-strings=no
    (call lines are inclusive costs of callees: skipped)."""
    binary = os.path.realpath(binary)
    total, ob, skip_next = 0, None, False
    with open(path) as f:
        for line in f:
            if not line or not (line[0].isdigit() or line[0] in "+-*"):
                if line.startswith("ob="):
                    ob = os.path.realpath(line[3:].strip())
                elif line.startswith("calls="):
                    skip_next = True
                continue
            if skip_next:
                skip_next = False
                continue
            if ob == binary:
                parts = line.split()
                if len(parts) >= 2:
                    total += int(parts[1])
    return total


def count(exe, workload, lipmwalk):
    """Own instructions of one workload. Run from the workspace root with
    paths relative to it and a minimal environment: the heap buffers of the
    `Dyn` workloads land at addresses that depend on both, and a few loops
    take a different number of steps with the alignment (the `n50_*` counts
    move by up to a few thousand, < 0.01 %, between checkouts)."""
    rel = lambda p: os.path.relpath(os.path.abspath(p), ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "callgrind.out")
        subprocess.run(
            ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out,
             "--collect-atstart=no", "--toggle-collect=*icount::counted*",
             "--compress-strings=no", "--compress-pos=no", "--dump-instr=no",
             rel(exe), workload, rel(lipmwalk)],
            cwd=ROOT, env={"PATH": os.environ.get("PATH", "/usr/bin:/bin")},
            check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        return own_instructions(out, os.path.join(ROOT, rel(exe)))


def read_baseline():
    base = {}
    if not os.path.exists(BASELINE):
        return base
    with open(BASELINE) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if line:
                name, value = line.split()
                base[name] = int(value)
    return base


def rustc_version():
    return subprocess.run(["rustc", "--version"], check=True, stdout=subprocess.PIPE,
                          text=True).stdout.strip()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lipmwalk", default=LIPMWALK,
                    help="folder of the LIPMWALK npz files (default: tests/data/lipmwalk)")
    ap.add_argument("--tolerance", type=float, default=0.03,
                    help="largest allowed relative growth of a count (default 0.03)")
    ap.add_argument("--update", action="store_true",
                    help="write the measured counts to benches/icount-baseline.txt")
    ap.add_argument("--bin", help="an icount binary already built (skips the build)")
    args = ap.parse_args()

    exe = args.bin or build()
    names = subprocess.run([exe, "list"], check=True, stdout=subprocess.PIPE,
                           text=True).stdout.split()
    counts = {w: count(exe, w, args.lipmwalk) for w in names}
    if args.update:
        with open(BASELINE, "w") as f:
            f.write("# Instruction counts of the workloads of benches/icount.rs, written by\n"
                    "# `python3 tools/icount.py --update` and checked by it in CI (3 % tolerance).\n"
                    "# Update deliberately: commit this file with the reason for the change.\n"
                    f"# Recorded with {rustc_version()}.\n")
            for w in names:
                f.write(f"{w} {counts[w]}\n")
        print(f"wrote {os.path.relpath(BASELINE, ROOT)}")
    base = read_baseline()
    grown = []
    print(f"{'workload':<16} {'baseline':>12} {'now':>12} {'change':>8}")
    for w in names:
        b = base.get(w)
        change = "" if b is None else f"{(counts[w] - b) / b:+.2%}"
        print(f"{w:<16} {b if b is not None else '-':>12} {counts[w]:>12} {change:>8}")
        if b is None or counts[w] > b * (1 + args.tolerance):
            grown.append(w)
    if grown:
        with open(BASELINE) if os.path.exists(BASELINE) else open(os.devnull) as f:
            recorded = next((l.strip("# \n") for l in f if "Recorded with" in l), "")
        print(f"\nFAIL: instruction counts grew by more than {args.tolerance:.0%} (or have no "
              f"baseline): {', '.join(grown)}.\n"
              "If the change is deliberate, record it: `python3 tools/icount.py --update`, "
              "then commit benches/icount-baseline.txt with the reason in the commit message.\n"
              f"({recorded}; this run: {rustc_version()}. A different compiler version can "
              "change the counts too.)", file=sys.stderr)
        return 1
    print(f"ok: every count within {args.tolerance:.0%} of the baseline")
    return 0


if __name__ == "__main__":
    sys.exit(main())
