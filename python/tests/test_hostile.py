"""Hostile input: recursion, absurd values, interrupts. Every case ends in
one exception naming the field (or passes a BaseException through), never a
crash, a hang or a silently wrong answer."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

import ldcbf_nav
from ldcbf_nav import ArgumentError, ScenarioError

BASE = {"name": "x", "start": {"x": 0.0, "y": 0.0}, "goal": [5.0, 5.0]}


def test_a_scenario_dict_that_contains_itself_is_refused():
    d = dict(BASE)
    d["robot"] = d
    with pytest.raises(ArgumentError, match="contains itself"):
        ldcbf_nav.load_scenario(d)


def test_a_deeply_nested_list_is_refused_before_recursing():
    deep = [1.0]
    for _ in range(20_000):
        deep = [deep]
    with pytest.raises(ArgumentError, match="nested more than"):
        ldcbf_nav.load_scenario({**BASE, "goal": deep})


@pytest.mark.parametrize("parts", [9, 50_000])
def test_override_keys_with_many_parts_are_refused(parts):
    key = ".".join(["a"] * parts)
    with pytest.raises(ScenarioError, match="dotted parts|too long") as info:
        ldcbf_nav.load_scenario("simple", **{key: 1})
    assert len(str(info.value)) < 400, "the key is not echoed whole"


def test_a_huge_key_is_not_echoed_whole():
    with pytest.raises(ScenarioError) as info:
        ldcbf_nav.load_scenario("simple", **{"k" * 1_000_000: 1})
    assert len(str(info.value)) < 400


@pytest.mark.parametrize(
    "overrides, field",
    [
        ({"goal": [5.0, 5.0, 7.0]}, "goal"),
        ({"goal": [5.0]}, "goal"),
        ({"goal": [1e300, 5.0]}, "goal[0]"),
        ({"gravity": 1e308}, "controller.gravity"),
        ({"generator": {"area_min": [0.0, 0.0, 0.0]}}, "generator"),
    ],
)
def test_bad_lengths_and_magnitudes_name_the_field(overrides, field):
    with pytest.raises(ScenarioError) as info:
        ldcbf_nav.load_scenario("simple", **overrides)
    assert info.value.field.startswith(field), str(info.value)


def test_a_bow_tie_is_self_intersecting_not_collinear():
    bow = [[1.0, 1.0], [2.0, 2.0], [2.0, 1.0], [1.0, 2.0]]
    with pytest.raises(ScenarioError) as info:
        ldcbf_nav.load_scenario({**BASE, "obstacles": [{"vertices": bow}]})
    assert "self-intersecting" in str(info.value)
    assert "collinear" not in str(info.value)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"tol_primal": 1e300}, "tol_primal"),
        ({"tol_primal": 0.0}, "tol_primal"),
        ({"tol_primal": float("nan")}, "tol_primal"),
        ({"tol_dependence": 1e300}, "tol_dependence"),
        ({"tol_dependence": -1.0}, "tol_dependence"),
        ({"tol_primal": True}, "tol_primal"),
        ({"max_iter": -1}, "max_iter"),
        ({"max_iter": 3.5}, "max_iter"),
        ({"max_iter": True}, "max_iter"),
        ({"max_iter": 0}, "max_iter"),
        ({"max_iter": 2**40}, "max_iter"),
    ],
)
def test_solver_limits_are_validated(kwargs, field):
    with pytest.raises(ArgumentError) as info:
        ldcbf_nav.solve_qp([[1.0]], [0.0], [[1.0]], [-2.0], **kwargs)
    assert info.value.field == field


@pytest.mark.parametrize("seed", [-1, 2.0, 3.5, True, "7", 2**64])
def test_bad_seeds_are_argument_errors(seed):
    with pytest.raises(ArgumentError) as info:
        ldcbf_nav.load_scenario("random", seed=seed)
    assert info.value.field == "seed"


def test_a_numpy_integer_seed_is_an_integer():
    np = pytest.importorskip("numpy")
    assert ldcbf_nav.load_scenario("random", seed=np.int64(3))["seed"] == 3


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"trajectory_every": -1}, "trajectory_every"),
        ({"trajectory_every": 1.5}, "trajectory_every"),
        ({"trajectory_every": False}, "trajectory_every"),
        ({"solver": 3}, "solver"),
    ],
)
def test_simulate_arguments_are_argument_errors(kwargs, field):
    with pytest.raises(ArgumentError) as info:
        ldcbf_nav.simulate("simple", **kwargs)
    assert info.value.field == field


class _Interrupting:
    def __float__(self):
        raise KeyboardInterrupt

    def __index__(self):
        raise KeyboardInterrupt


@pytest.mark.parametrize(
    "call",
    [
        lambda: ldcbf_nav.solve_qp([[_Interrupting()]], [0.0]),
        lambda: ldcbf_nav.solve_qp([[1.0]], [0.0], tol_primal=_Interrupting()),
        lambda: ldcbf_nav.solve_qp([[1.0]], [0.0], max_iter=_Interrupting()),
        lambda: ldcbf_nav.load_scenario("random", seed=_Interrupting()),
        lambda: ldcbf_nav.Controller({"gamma": _Interrupting()}),
    ],
)
def test_keyboard_interrupt_in_a_conversion_passes_through(call):
    with pytest.raises(KeyboardInterrupt):
        call()


def test_ctrl_c_stops_simulate_within_a_second():
    # A walk to a goal 1.2 km away: minutes of simulation without the signal.
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    t0 = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            ldcbf_nav.simulate(
                "simple", goal=[900.0, 900.0], time_limit=1e5, stuck_window=0.0
            )
    finally:
        timer.cancel()
    assert time.monotonic() - t0 < 0.5 + 1.0
