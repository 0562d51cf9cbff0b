"""A bad argument raises a Python exception naming the field, never a crash."""

from __future__ import annotations

import math

import numpy as np
import pytest

import ldcbf_nav
from ldcbf_nav import ArgumentError, ConfigError, Controller, ScenarioError

SQUARE = [[1.0, -0.5], [2.0, -0.5], [2.0, 0.5], [1.0, 0.5]]


def step_args(**changes):
    args = dict(
        com_position=[0.0, 0.0],
        com_velocity=[0.0, 0.0],
        heading=0.0,
        turning_rate=0.0,
        stance_foot=[0.0, 0.0],
        stance_side="left",
        time_in_step=0.0,
        goal=[5.0, 0.0],
        obstacles=[SQUARE],
    )
    args.update(changes)
    return args


def raises_naming(exc, field, fn, *args, **kwargs):
    with pytest.raises(exc) as info:
        fn(*args, **kwargs)
    e = info.value
    assert e.field == field, f"field {e.field!r}, expected {field!r} ({e})"
    assert field in str(e), str(e)
    return e


@pytest.mark.parametrize(
    "config, field",
    [
        ({"gamma": 2.0}, "gamma"),
        ({"gamma": float("nan")}, "gamma"),
        ({"com_height": -1.0}, "com_height"),
        ({"gamma": "0.3"}, "gamma"),
        ({"max_iter": -1}, "max_iter"),
        ({"max_iter": 1.5}, "max_iter"),
        ({"max_iter_cycle": 1}, "max_iter_cycle"),
        ({"warm_start": 1}, "warm_start"),
        ({"foot_clearance": float("inf")}, "foot_clearance"),
        ({"capture_fraction": 1.5}, "capture_fraction"),
        ({"no_such_setting": 1.0}, "no_such_setting"),
    ],
)
def test_bad_config_names_the_setting(config, field):
    e = raises_naming(ConfigError, field, Controller, config)
    assert isinstance(e, ValueError)


def test_foot_rows_need_the_robot_size():
    raises_naming(ConfigError, "foot_clearance", Controller, {"foot_clearance": 0.0}, size="paper")
    Controller({"foot_clearance": 0.0}, size="robot")  # room for the foot rows


def test_bad_controller_arguments():
    raises_naming(ArgumentError, "size", Controller, None, size="huge")
    raises_naming(ArgumentError, "config", Controller, [("gamma", 0.3)])


@pytest.mark.parametrize(
    "changes, field",
    [
        ({"com_position": [1.0, 2.0, 3.0]}, "com_position"),
        ({"com_position": "here"}, "com_position"),
        ({"com_velocity": None}, "com_velocity"),
        ({"heading": "north"}, "heading"),
        ({"heading": [0.0, 1.0]}, "heading"),
        ({"turning_rate": True}, "turning_rate"),
        ({"stance_foot": [[0.0, 0.0]]}, "stance_foot"),
        ({"stance_side": "middle"}, "stance_side"),
        ({"stance_side": 1}, "stance_side"),
        ({"time_in_step": None}, "time_in_step"),
        ({"goal": [1.0]}, "goal"),
        ({"obstacles": 5}, "obstacles"),
        ({"obstacles": [SQUARE, [[0.0, 0.0], [1.0, 0.0]]]}, "obstacles[1]"),
        ({"obstacles": [[[0, 0], [1, 1], [1, 0], [0, 1]]]}, "obstacles[0]"),
        ({"obstacles": [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]]}, "obstacles[0]"),
        ({"obstacles": [[[0, 0], [1, 0], [float("nan"), 1]]]}, "obstacles[0]"),
        ({"obstacles": [[[math.cos(a), math.sin(a)] for a in np.linspace(0, 6.2, 40)]]}, "obstacles[0]"),
    ],
)
def test_bad_step_input_names_the_argument(changes, field):
    ctl = Controller()
    raises_naming(ArgumentError, field, ctl.step, **step_args(**changes))


def test_a_bad_measurement_is_the_controllers_answer_not_an_exception():
    ctl = Controller()
    out = ctl.step(**step_args(com_position=[float("nan"), 0.0]))
    assert out["status"] == "invalid_input"
    assert out["input_error"] == "state"
    assert out["info"]["source"] == "hold"
    assert np.all(np.isfinite(out["foot_target"]))
    out = ctl.step(**step_args(goal=[1e300, 0.0]))
    assert (out["status"], out["input_error"]) == ("invalid_input", "goal")


def test_bad_scenarios_name_the_field(in_repo):
    e = raises_naming(ScenarioError, "controller.gamma", ldcbf_nav.simulate, "simple", gamma=5.0)
    assert isinstance(e, ValueError)
    raises_naming(ScenarioError, "no_such_key", ldcbf_nav.simulate, "simple", no_such_key=1)
    raises_naming(ScenarioError, "goal", ldcbf_nav.load_scenario, "simple", goal=[2.6, 2.4])
    with pytest.raises(ScenarioError, match="no scenario named"):
        ldcbf_nav.simulate("no-such-scenario")
    with pytest.raises(ScenarioError, match="missing field `name`"):
        ldcbf_nav.simulate({"start": {"x": 0, "y": 0}, "goal": [1, 1]})
    raises_naming(
        ScenarioError,
        "obstacles[0].vertices",
        ldcbf_nav.load_scenario,
        {"name": "x", "start": {"x": 0, "y": 0}, "goal": [5, 5],
         "obstacles": [{"vertices": [[1, 1], [2, 2], [2, 1], [1, 2]]}]},
    )
    raises_naming(ArgumentError, "scenario", ldcbf_nav.simulate, 42)
    raises_naming(ArgumentError, "time_limit", ldcbf_nav.simulate, "simple", time_limit=None)


def test_bad_simulate_options(in_repo):
    raises_naming(ArgumentError, "solver", ldcbf_nav.simulate, "simple", solver="gurobi")
    raises_naming(ArgumentError, "mpc_rate", ldcbf_nav.simulate, "simple", mpc_rate=0)
    raises_naming(ArgumentError, "mpc_rate", ldcbf_nav.simulate, "simple", mpc_rate="fast")
    raises_naming(ArgumentError, "trajectory_every", ldcbf_nav.simulate, "simple", trajectory_every=0)


def test_bad_qp_arguments_name_the_matrix():
    P, q = 2 * np.eye(6), -np.ones(6)
    G, h = np.ones((1, 6)), np.ones(1)
    raises_naming(ArgumentError, "P", ldcbf_nav.solve_qp, np.ones((6, 5)), q)
    raises_naming(ArgumentError, "P", ldcbf_nav.solve_qp, -P, q)  # not positive definite
    raises_naming(ArgumentError, "P", ldcbf_nav.solve_qp, P + np.triu(np.ones((6, 6)), 1), q)  # not symmetric
    raises_naming(ArgumentError, "q", ldcbf_nav.solve_qp, P, np.ones(5))
    raises_naming(ArgumentError, "q", ldcbf_nav.solve_qp, P, [1, 2, 3, 4, 5, float("nan")])
    raises_naming(ArgumentError, "G", ldcbf_nav.solve_qp, P, q, np.ones((2, 6)), h)
    raises_naming(ArgumentError, "h", ldcbf_nav.solve_qp, P, q, G, np.ones((1, 1)))
    raises_naming(ArgumentError, "h", ldcbf_nav.solve_qp, P, q, G, None)
    raises_naming(ArgumentError, "G", ldcbf_nav.solve_qp, P, q, None, h)
    raises_naming(ArgumentError, "P", ldcbf_nav.solve_qp, "P", q)
    raises_naming(ArgumentError, "tol_primal", ldcbf_nav.solve_qp, P, q, tol_primal=0.0)


def test_an_uncompiled_size_is_solved_by_the_dynamic_instance():
    # n = 7 has no compiled size; nor has n = 6 with more rows than any.
    r = ldcbf_nav.solve_qp(2 * np.eye(7), -2 * np.ones(7))
    assert (r["status"], r["path"]) == ("solved", "dynamic")
    assert np.allclose(r["x"], np.ones(7))
    most = max(m for n, m in ldcbf_nav.QP_SIZES if n == 6)
    G = np.vstack([np.eye(6)] * (most // 6 + 1))
    r = ldcbf_nav.solve_qp(2 * np.eye(6), -2 * np.ones(6), G, 0.5 * np.ones(len(G)))
    assert (r["status"], r["path"]) == ("solved", "dynamic")
    assert np.allclose(r["x"], 0.5 * np.ones(6))
    assert len(r["lambda"]) == len(G)
    r = ldcbf_nav.solve_qp(2 * np.eye(6), -2 * np.ones(6), np.eye(6), np.ones(6))
    assert r["path"] == "static"


JUNK = [None, "x", 1, 1.5, True, [1], [[1, 2]], {"a": 1}, object(), np.zeros((3, 3)), float("nan")]


def test_junk_never_crashes():
    """Every argument of every entry point, given junk: an Exception, never a
    panic (PyO3's PanicException is a BaseException) or a crash."""
    ctl = Controller()
    base = step_args()
    for key in base:
        for junk in JUNK:
            try:
                ctl.step(**dict(base, **{key: junk}))
            except Exception:
                pass
    P, q = 2 * np.eye(6), -np.ones(6)
    for i in range(4):
        for junk in JUNK:
            args = [P, q, np.ones((1, 6)), np.ones(1)]
            args[i] = junk
            try:
                ldcbf_nav.solve_qp(*args)
            except Exception:
                pass
    for junk in JUNK:
        for fn in (Controller, ldcbf_nav.simulate, ldcbf_nav.load_scenario):
            try:
                fn(junk)
            except Exception:
                pass
