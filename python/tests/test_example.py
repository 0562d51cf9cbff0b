"""The example closes the loop from Python and reaches the goal."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "lip_loop.py"


def test_lip_loop_reaches_the_goal(in_repo):
    p = subprocess.run([sys.executable, str(EXAMPLE), "paper"], capture_output=True, text=True, cwd=in_repo)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "scenario paper: goal reached" in p.stdout, p.stdout
