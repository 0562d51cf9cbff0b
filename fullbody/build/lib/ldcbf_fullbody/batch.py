"""``python3 -m ldcbf_fullbody batch --family F --seeds A..B [--shard I/N]``:
many seeds of a scenario family, one full-body run each, sharded as
``ldcbf-sim batch`` (interleaved: seed number ``k`` from ``A`` belongs to
shard ``I`` of ``N`` when ``k mod N == I - 1``)."""

import csv
import pathlib
from typing import Any, Callable, Dict, List, Tuple

#: The summary fields written to ``runs.csv``, in order.
COLUMNS = (
    "seed",
    "reached_goal",
    "falls",
    "link_contacts",
    "landing_error_p95_m",
    "min_clearance_3d_m",
    "steps",
    "sim_time",
    "real_time_factor",
    "error",
)


def seed_range(text: str) -> Tuple[int, int]:
    """``A..B`` (B excluded), ``A..=B`` or one seed ``A``: ``(start, end)``."""
    try:
        if "..=" in text:
            a, b = text.split("..=")
            start, end = int(a), int(b) + 1
        elif ".." in text:
            a, b = text.split("..")
            start, end = int(a), int(b)
        else:
            start = int(text)
            end = start + 1
    except ValueError:
        raise ValueError(f"--seeds {text!r}: expected A..B, A..=B or one seed") from None
    if start < 0 or end <= start:
        raise ValueError(f"--seeds {text!r}: an empty or negative range")
    return start, end


def shard(text: str) -> Tuple[int, int]:
    """``I/N`` with ``1 <= I <= N``."""
    try:
        i, n = (int(x) for x in text.split("/"))
    except ValueError:
        raise ValueError(f"--shard {text!r}: expected I/N") from None
    if not 1 <= i <= n:
        raise ValueError(f"--shard {text!r}: needs 1 <= I <= N")
    return i, n


def shard_seeds(seeds: Tuple[int, int], part: Tuple[int, int]) -> List[int]:
    """The seeds of the range held by shard ``part`` (interleaved)."""
    start, end = seeds
    index, count = part
    return [s for s in range(start, end) if (s - start) % count == index - 1]


def run_batch(
    family: str, seeds: List[int], pairs: List[str], out: pathlib.Path, run_one: Callable[..., Dict[str, Any]]
) -> List[Dict[str, Any]]:
    """One run per seed into ``out/seed-<s>/``; ``out/runs.csv`` one row per
    seed (a run that raised has its message in ``error``)."""
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for seed in seeds:
        try:
            summary = run_one(family, pairs, out / f"seed-{seed}", seed, True)
            row = {k: summary.get(k) for k in COLUMNS}
            row["error"] = ""
        except (ValueError, RuntimeError) as e:
            row = {k: None for k in COLUMNS}
            row["error"] = str(e)
        row["seed"] = seed
        rows.append(row)
        print(" ".join(f"{k}={row[k]}" for k in COLUMNS if row[k] not in (None, "")), flush=True)
    with open(out / "runs.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    return rows


def verdict(rows: List[Dict[str, Any]]) -> str:
    """One line: runs, goals reached with no fall and no link contact."""
    good = sum(1 for r in rows if r["reached_goal"] and r["falls"] == 0 and r["link_contacts"] == 0)
    falls = sum(1 for r in rows if r["falls"])
    touched = sum(1 for r in rows if r["link_contacts"])
    return f"{len(rows)} runs: {good} reached the goal with no fall and no link contact; {falls} fell; {touched} touched an obstacle"
