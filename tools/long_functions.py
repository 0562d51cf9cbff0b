#!/usr/bin/env python3
"""Lists the non-test Rust functions longer than a threshold.

    python3 tools/long_functions.py            # functions over 80 lines, longest first
    python3 tools/long_functions.py --over 150
    python3 tools/long_functions.py --count    # only the counts over 80 and over 150

A function's length is the number of lines from its `fn` line to its closing
brace. Test code is left out: `tests/`, `benches/`, `examples/`, `fuzz/`,
files named `tests.rs` or under a `tests/` folder, and `#[cfg(test)]` modules.
Tracked files only (`git ls-files`), from the repository root.
"""

import argparse
import re
import subprocess
import sys

SKIP_DIRS = ("tests/", "benches/", "examples/", "fuzz/")
FN = re.compile(r"\bfn\s+([A-Za-z_][A-Za-z0-9_]*)")


def strip(src):
    """`src` with comments, strings and char literals blanked (newlines kept),
    so braces can be counted."""
    out = []
    i, n = 0, len(src)
    while i < n:
        c = src[i]
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif src.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if src.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif src.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", src[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', src[i:]) and not (i and (src[i - 1].isalnum() or src[i - 1] == "_")):
            hashes = re.match(r"r(#*)\"", src[i:]).group(1)
            end = src.find('"' + hashes, i + 2 + len(hashes))
            j = n if end < 0 else end + 1 + len(hashes)
            out.append(re.sub(r"[^\n]", " ", src[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and src[j] != '"':
                j += 2 if src[j] == "\\" else 1
            out.append(re.sub(r"[^\n]", " ", src[i : j + 1]))
            i = j + 1
        elif c == "'":
            # A char literal ('x', '\n', '\u{..}') or a lifetime ('a).
            m = re.match(r"'(\\.[^']*|[^\\'])'", src[i:])
            if m:
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def match_brace(s, i):
    depth = 0
    for j in range(i, len(s)):
        if s[j] == "{":
            depth += 1
        elif s[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(s) - 1


def test_spans(s):
    """Character spans of `#[cfg(test)]` items (modules, functions)."""
    spans = []
    for m in re.finditer(r"#\[cfg\(test\)\]", s):
        # The item's body: the first `{` or `;` after the attribute.
        j = m.end()
        while j < len(s) and s[j] not in "{;":
            j += 1
        if j < len(s) and s[j] == "{":
            spans.append((m.start(), match_brace(s, j)))
    return spans


def functions(path):
    src = open(path, encoding="utf-8").read()
    s = strip(src)
    skip = test_spans(s)
    for m in FN.finditer(s):
        if any(a <= m.start() <= b for a, b in skip):
            continue
        # The body opens at the first `{` after the signature unless a `;`
        # comes first (a declaration in a trait).
        j = m.end()
        while j < len(s) and s[j] not in "{;":
            j += 1
        if j >= len(s) or s[j] == ";":
            continue
        end = match_brace(s, j)
        first = s.count("\n", 0, m.start()) + 1
        last = s.count("\n", 0, end) + 1
        yield m.group(1), first, last - first + 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--over", type=int, default=80, help="list functions longer than this (lines)")
    ap.add_argument("--count", action="store_true", help="print only the counts over 80 and 150")
    args = ap.parse_args()
    files = subprocess.run(
        ["git", "ls-files", "*.rs"], capture_output=True, text=True, check=True
    ).stdout.split()
    rows = []
    for f in files:
        if f.startswith(SKIP_DIRS) or "/tests/" in f or f.endswith("/tests.rs") or "/examples/" in f:
            continue
        for name, line, length in functions(f):
            rows.append((length, f, line, name))
    rows.sort(key=lambda r: (-r[0], r[1], r[2]))
    if args.count:
        print(f"functions: {len(rows)}; over 80 lines: {sum(r[0] > 80 for r in rows)}; "
              f"over 150: {sum(r[0] > 150 for r in rows)}")
        return 0
    for length, f, line, name in rows:
        if length > args.over:
            print(f"{length:5d}  {f}:{line}  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
