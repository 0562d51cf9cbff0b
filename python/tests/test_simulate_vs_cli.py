"""`ldcbf_nav.simulate` against the CLI: the same run, the same logs.

`ldcbf-sim run NAME --out DIR` writes `cycles.csv`, `footsteps.csv`,
`trajectory.csv` and `summary.json`; `simulate(NAME)` must return the same
numbers: every float column bit for bit (the CSV prints the shortest
representation that reads back as the same float), the times (printed with 3
decimals) to their printed digits, and the same summary except the wall-clock
timings.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import ldcbf_nav

# Columns printed with "{:.3}" by the CLI.
ROUNDED = {"t", "time_in_step"}
# Wall-clock measurements: differ from run to run.
TIMINGS = {"compute_ns"}
INTS = {"step", "active_obstacles", "truncated", "iterations", "active_set", "landed"}
STRINGS = {"stance", "status", "source", "side"}


def same_float(a: float, b: float) -> bool:
    """Bit for bit (NaN equals NaN)."""
    return float(a).hex() == float(b).hex()


def check_columns(name: str, csv_cols, py_cols):
    for col, texts in csv_cols.items():
        if col in TIMINGS:
            continue
        assert col in py_cols, f"{name}: column {col} missing from simulate()"
        values = py_cols[col]
        assert len(values) == len(texts), f"{name}.{col}: {len(values)} rows vs {len(texts)}"
        for k, (text, v) in enumerate(zip(texts, values)):
            if col in ROUNDED:
                ok = f"{float(v):.3f}" == text
            elif col in INTS:
                ok = int(v) == int(text)
            elif col in STRINGS:
                ok = str(v) == text
            else:
                ok = same_float(float(text), float(v))
            assert ok, f"{name}.{col}[{k}]: CLI {text!r}, simulate {v!r}"


def same_json(a, b, path=""):
    """Equal JSON values; floats bit for bit (NaN equals NaN)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), f"{path}: keys {a.keys()} vs {b}"
        for k in a:
            same_json(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, float) or isinstance(b, float):
        assert isinstance(a, (int, float)) and isinstance(b, (int, float)), f"{path}: {a!r} vs {b!r}"
        assert same_float(a, b), f"{path}: {a!r} vs {b!r}"
    else:
        assert a == b, f"{path}: {a!r} vs {b!r}"


@pytest.mark.parametrize("name", ["simple", "paper"])
def test_simulate_matches_the_cli(name, cli_runs, in_repo):
    cli = cli_runs(name)  # the CLI's default: every 10th sample in trajectory.csv
    res = ldcbf_nav.simulate(name, trajectory_every=10)
    check_columns("cycles", cli.cycles, res["cycles"])
    check_columns("footsteps", cli.footsteps, res["footsteps"])
    check_columns("trajectory", cli.trajectory, res["trajectory"])
    ours = dict(res["summary"])
    theirs = dict(cli.summary)
    for key in ("compute", "plan_time_ms"):  # wall-clock timings
        ours.pop(key)
        theirs.pop(key)
    same_json(theirs, ours)
    assert res["outcome"] == cli.summary["ended"]
    # Not an empty comparison: the run walked.
    assert len(res["cycles"]["t"]) > 50 and res["summary"]["steps"] > 10


def test_overrides_are_the_clis_set(cli_runs, in_repo):
    args = ("--set", "time_limit=6", "--set", "controller.delta=0.1", "--seed", "3")
    cli = cli_runs("simple", *args)
    res = ldcbf_nav.simulate("simple", seed=3, time_limit=6, controller__delta=0.1, trajectory_every=10)
    check_columns("cycles", cli.cycles, res["cycles"])
    assert res["summary"]["config"]["delta"] == 0.1 == cli.summary["config"]["delta"]
    assert res["summary"]["overrides"] == cli.summary["overrides"]
    assert math.isclose(res["summary"]["sim_time"], 6.0, abs_tol=1e-3)
    # The dotted spelling is the same override.
    res2 = ldcbf_nav.simulate("simple", seed=3, **{"time_limit": 6, "controller.delta": 0.1})
    assert np.array_equal(res2["cycles"]["foot_x"], res["cycles"]["foot_x"])


def test_dict_scenario_is_the_file(in_repo):
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

    with open(in_repo / "scenarios" / "simple.toml", "rb") as f:
        table = tomllib.load(f)
    table["time_limit"] = 8.0
    from_dict = ldcbf_nav.simulate(table)
    from_file = ldcbf_nav.simulate("simple", time_limit=8.0)
    assert from_dict["summary"]["source"] == "<dict>"
    for col in ("foot_x", "foot_y", "omega", "cost"):
        a, b = from_dict["cycles"][col], from_file["cycles"][col]
        assert a.tobytes() == b.tobytes(), col
    assert from_dict["outcome"] == from_file["outcome"]


def test_columns_are_numpy(in_repo):
    res = ldcbf_nav.simulate("simple", time_limit=3)
    cy = res["cycles"]
    assert cy["foot_x"].dtype == np.float64
    assert cy["iterations"].dtype == np.int64
    assert cy["landed"].dtype == np.bool_
    assert cy["status"].dtype.kind == "U"
    n = len(cy["t"])
    assert all(len(v) == n for v in cy.values())
    # trajectory_every=1 keeps every 1 kHz sample.
    assert len(res["trajectory"]["t"]) == round(res["summary"]["sim_time"] * 1000) + 1
    assert res["subgoals"].shape == (1, 2)


def test_solver_and_rate_options(in_repo):
    clar = ldcbf_nav.simulate("simple", solver="clarabel", time_limit=2)
    assert clar["summary"]["solver"] == "clarabel"
    per_step = ldcbf_nav.simulate("simple", mpc_rate="step", time_limit=2)
    assert per_step["summary"]["mpc_rate"] == "once per step"
    # One cycle at the start of each 0.4 s step (the last at the 2 s limit).
    np.testing.assert_allclose(per_step["cycles"]["t"], np.arange(6) * 0.4, atol=1e-12)
    at10 = ldcbf_nav.simulate("simple", mpc_rate=10, time_limit=2)
    np.testing.assert_allclose(at10["cycles"]["t"], np.arange(21) * 0.1, atol=1e-12)
    at20 = ldcbf_nav.simulate("simple", time_limit=2)
    np.testing.assert_allclose(at20["cycles"]["t"], np.arange(41) * 0.05, atol=1e-12)
