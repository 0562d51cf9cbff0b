#!/usr/bin/env python3
"""Lists the panicking call sites that survive optimisation in an ARM ELF.

Usage: list_panics.py OBJDUMP ADDR2LINE ELF

Disassembles ELF (built with panic-halt and debug info, see check.sh --list),
finds every function from which the panic handler (`rust_begin_unwind`) can be
reached, and prints each branch from a non-`core` function into one of them,
with the inlined source chain of the branch from addr2line. Exit status: 0 when
there is none, 1 otherwise.
"""

import re
import subprocess
import sys

FUNC = re.compile(r"^([0-9a-f]+) <(.*)>:$")
# Any branch (bl, b.w, bhs.w, cbz, ...) whose target is the start of a symbol.
BRANCH = re.compile(r"^\s*([0-9a-f]+):\s+(b[a-z.]*|cbn?z)\s.*<([^>+]*)>\s*(@.*)?$")
HANDLER = "rust_begin_unwind"


def main() -> int:
    objdump, addr2line, elf = sys.argv[1:4]
    asm = subprocess.run(
        [objdump, "-d", "-C", "--no-show-raw-insn", elf],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    calls = {}  # function -> [(address, target)]
    cur = None
    for line in asm.splitlines():
        m = FUNC.match(line)
        if m:
            cur = m.group(2)
            calls.setdefault(cur, [])
            continue
        m = BRANCH.match(line)
        if m and cur is not None and m.group(3) != cur:
            calls[cur].append((m.group(1), m.group(3)))
    # Reverse reachability of the panic handler.
    handlers = [f for f in calls if f.endswith(HANDLER)]
    panicky = set(handlers)
    changed = True
    while changed:
        changed = False
        for f, cs in calls.items():
            if f not in panicky and any(t in panicky for _, t in cs):
                panicky.add(f)
                changed = True
    sites = [
        (a, f, t)
        for f, cs in calls.items()
        if not f.startswith("core::") and f not in handlers
        for a, t in cs
        # Only branches into core's panic machinery: a call to another
        # panicking function of the program is listed at that function's sites.
        if t in panicky and (t.startswith("core::") or t in handlers)
    ]
    if not handlers:
        print("no panic handler in the binary: nothing can panic")
        return 0
    for a, f, t in sites:
        chain = subprocess.run(
            [addr2line, "-i", "-f", "-C", "-e", elf, "0x" + a],
            check=True,
            capture_output=True,
            text=True,
        ).stdout.splitlines()
        print(f"0x{a} in {f}\n    -> {t}")
        # addr2line -f prints (function, file:line) pairs, innermost first.
        for fn, loc in zip(chain[0::2], chain[1::2]):
            print(f"    at {loc}  ({fn})")
    print(f"{len(sites)} panicking call site(s)")
    return 1 if sites else 0


if __name__ == "__main__":
    sys.exit(main())
