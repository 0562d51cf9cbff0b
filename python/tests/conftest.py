"""Shared fixtures: the repository root and the `ldcbf-sim` CLI.

The CLI is the one the Rust workspace builds: ``$LDCBF_SIM`` when set (a path
to the `ldcbf-sim` binary), else ``cargo run --release -q -p ldcbf-sim --``
from the repository root.
"""

from __future__ import annotations

import csv
import json
import os
import shlex
import subprocess
from pathlib import Path
from typing import Dict, List

import pytest

REPO = Path(__file__).resolve().parents[2]


def cli_command() -> List[str]:
    """The command that runs `ldcbf-sim`."""
    exe = os.environ.get("LDCBF_SIM")
    if exe:
        return shlex.split(exe)
    return ["cargo", "run", "--release", "--locked", "-q", "-p", "ldcbf-sim", "--"]


def run_cli(*args: str) -> subprocess.CompletedProcess:
    """Runs `ldcbf-sim ARGS` in the repository root; fails the test on an error."""
    p = subprocess.run(
        cli_command() + list(args), cwd=REPO, capture_output=True, text=True
    )
    assert p.returncode == 0, f"ldcbf-sim {' '.join(args)} failed:\n{p.stderr}"
    return p


def read_csv(path: Path) -> Dict[str, List[str]]:
    """A CSV file as columns of strings."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    assert rows, f"{path} has no rows"
    return {k: [r[k] for r in rows] for k in rows[0]}


class CliRun:
    """One `ldcbf-sim run` and its output directory."""

    def __init__(self, out: Path):
        self.out = out
        self.summary = json.loads((out / "summary.json").read_text())
        self.cycles = read_csv(out / "cycles.csv")
        self.footsteps = read_csv(out / "footsteps.csv")
        self.trajectory = read_csv(out / "trajectory.csv")


@pytest.fixture(scope="session")
def cli_runs(tmp_path_factory):
    """`ldcbf-sim run NAME --no-plots [ARGS]` outputs, memoised per argument list."""
    cache: Dict[tuple, CliRun] = {}

    def get(name: str, *args: str) -> CliRun:
        key = (name,) + args
        if key not in cache:
            out = tmp_path_factory.mktemp(name) / "out"
            run_cli("run", name, "--out", str(out), "--no-plots", *args)
            cache[key] = CliRun(out)
        return cache[key]

    return get


@pytest.fixture
def in_repo(monkeypatch):
    """Runs the test from the repository root (scenario names resolve as for the CLI)."""
    monkeypatch.chdir(REPO)
    return REPO
