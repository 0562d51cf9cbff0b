"""`Controller.step(..., obstacle_velocities=...)`: moving obstacles.

`data/moving_cycles.txt` holds 80 cycles of the humanoid controller with three
moving obstacles, inputs and outputs as f64 bits, written by the Rust
controller (`tests/moving_fixture.rs`, which checks that the file
is its output today). The same inputs through a fresh Python `Controller`, in
order, give the same outputs bit for bit.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest

import ldcbf_nav
from ldcbf_nav import Controller

DATA = Path(__file__).parent / "data" / "moving_cycles.txt"
HUMANOID = {"body_radius": 0.25, "foot_length": 0.22, "foot_width": 0.10, "foot_clearance": 0.0}


def f64(h: str) -> float:
    return struct.unpack(">d", bytes.fromhex(h))[0]


def bits(x: float) -> str:
    return struct.pack(">d", float(x)).hex()


def read_fixture():
    obstacles, velocities, cycles = [], [], []
    for line in DATA.read_text().splitlines():
        w = line.split()
        if not w or w[0] == "#":
            continue
        if w[0] == "obstacle":
            xs = [f64(h) for h in w[1:]]
            obstacles.append(np.array(xs).reshape(-1, 2))
        elif w[0] == "velocity":
            velocities.append([f64(w[1]), f64(w[2])])
        else:
            assert w[0] == "cycle" and w[13] == "->", line
            cycles.append(([f64(h) for h in w[1:13]], w[14:19], w[19], w[20]))
    return obstacles, np.array(velocities), cycles


def test_moving_cycles_match_the_rust_controller():
    obstacles, velocities, cycles = read_fixture()
    assert len(obstacles) == len(velocities) == 3 and len(cycles) == 80
    ctl = Controller(HUMANOID, size="robot")
    for k, (x, expect, status, source) in enumerate(cycles):
        out = ctl.step(
            com_position=x[0:2],
            com_velocity=x[2:4],
            heading=x[4],
            turning_rate=x[5],
            stance_foot=x[6:8],
            stance_side="left" if x[8] == 0.0 else "right",
            time_in_step=x[9],
            goal=x[10:12],
            obstacles=obstacles,
            obstacle_velocities=velocities,
        )
        got = [
            out["foot_target"][0],
            out["foot_target"][1],
            out["turning_rate"],
            out["info"]["min_h0"],
            out["info"]["cost"],
        ]
        assert [bits(g) for g in got] == expect, f"cycle {k}"
        assert (out["status"], out["info"]["source"]) == (status, source), f"cycle {k}"


SQUARE = [[1.0, -0.5], [1.5, -0.5], [1.5, 0.5], [1.0, 0.5]]
START = dict(
    com_position=[0.0, 0.0],
    com_velocity=[0.3, 0.0],
    heading=0.0,
    turning_rate=0.0,
    stance_foot=[0.0, -0.1],
    stance_side="left",
    time_in_step=0.1,
    goal=[5.0, 0.0],
    obstacles=[SQUARE],
)


def test_at_rest_is_no_velocities():
    a, b = (Controller(HUMANOID) for _ in range(2))
    for t in (0.0, 0.1, 0.3):
        args = dict(START, time_in_step=t)
        none = a.step(**args)
        zeros = b.step(**args, obstacle_velocities=[[0.0, 0.0]])
        assert zeros["foot_target"].tobytes() == none["foot_target"].tobytes()
        assert bits(zeros["info"]["cost"]) == bits(none["info"]["cost"])


@pytest.mark.parametrize("empty", [[], np.zeros((0, 2)), np.zeros(0)])
def test_no_velocities_for_obstacles_is_a_count_mismatch(empty):
    """An empty array given with obstacles is a count mismatch like any
    other (None is "all at rest"); without obstacles it is the empty list."""
    out = Controller(HUMANOID).step(**START, obstacle_velocities=empty)
    assert (out["status"], out["input_error"]) == (
        "invalid_input",
        "obstacle_velocity_count",
    )
    assert out["info"]["source"] == "hold"
    free = dict(START, obstacles=[])
    out = Controller(HUMANOID).step(**free, obstacle_velocities=empty)
    ref = Controller(HUMANOID).step(**free)
    assert out["foot_target"].tobytes() == ref["foot_target"].tobytes()


def test_bad_velocities_are_the_controllers_answer():
    ctl = Controller()
    out = ctl.step(**START, obstacle_velocities=[[0.1, 0.0], [0.0, 0.0]])
    assert out["status"] == "invalid_input"
    assert out["input_error"] == "obstacle_velocity_count"
    out = ctl.step(**START, obstacle_velocities=[[math.nan, 0.0]])
    assert out["input_error"] == "obstacle_velocity"
    assert out["info"]["source"] == "hold"


@pytest.mark.parametrize("bad", [[0.1, 0.0], [[0.1, 0.0, 0.0]], "fast", [["a", "b"]]])
def test_bad_velocity_shapes_name_the_argument(bad):
    with pytest.raises(ldcbf_nav.ArgumentError, match="obstacle_velocities"):
        Controller().step(**START, obstacle_velocities=bad)


def test_velocity_radii_widen_the_barrier_and_bad_ones_are_the_controllers_answer():
    """`obstacle_velocity_radii`: zeros (or None) are the known velocities bit
    for bit; a radius moves the plan (the set the person can reach); a NaN,
    negative or miscounted radius is an input error with the hold command."""
    ctl = Controller()
    v = [[0.0, 0.0]]
    known = ctl.step(**START, obstacle_velocities=v)
    ctl.reset()
    zeros = ctl.step(**START, obstacle_velocities=v, obstacle_velocity_radii=[0.0])
    assert zeros["foot_target"].tobytes() == known["foot_target"].tobytes()
    ctl.reset()
    wide = ctl.step(**START, obstacle_velocities=v, obstacle_velocity_radii=[1.5])
    assert wide["status"] != "invalid_input"
    assert wide["plan"]["states"].tobytes() != known["plan"]["states"].tobytes()
    for bad, name in (
        ([math.nan], "obstacle_velocity_radius"),
        ([-0.1], "obstacle_velocity_radius"),
        ([0.1, 0.2], "obstacle_velocity_radius_count"),
    ):
        out = Controller().step(**START, obstacle_velocities=v, obstacle_velocity_radii=bad)
        assert out["status"] == "invalid_input"
        assert out["input_error"] == name
        assert out["info"]["source"] == "hold"
    with pytest.raises(ldcbf_nav.ArgumentError, match="obstacle_velocity_radii"):
        Controller().step(**START, obstacle_velocity_radii=[[0.1]])
