"""`ldcbf_nav.Controller`: configuration, outputs, memory."""

from __future__ import annotations

import numpy as np

import ldcbf_nav
from ldcbf_nav import Controller

PAPER = [  # the paper scenario's obstacles (convex hulls, listed convex here)
    [[2.0, 7.5], [1.5, 7.0], [1.8, 6.5]],
    [[4.0, 6.5], [4.3, 6.8], [4.7, 6.5], [4.5, 6.2], [4.1, 6.2]],
    [[7.0, 7.0], [7.5, 7.5], [8.0, 7.0], [7.5, 6.5]],
    [[6.0, 2.5], [6.5, 2.0], [7.0, 2.5]],
    [[1.5, 3.0], [1.8, 3.3], [2.2, 3.0], [2.0, 2.6], [1.6, 2.6]],
    [[2.5, 3.5], [2.8, 3.8], [3.2, 3.5], [3.0, 3.1], [2.6, 3.1]],
]

START = dict(
    com_position=np.zeros(2),
    com_velocity=np.zeros(2),
    heading=0.0,
    turning_rate=0.0,
    stance_foot=np.zeros(2),
    stance_side="left",
    time_in_step=0.0,
    goal=np.array([10.0, 10.0]),
    obstacles=[np.array(o) for o in PAPER],
)


def test_config_round_trip():
    assert Controller().config == ldcbf_nav.default_config()
    assert list(ldcbf_nav.default_config()) == ldcbf_nav.CONFIG_FIELDS
    hum = ldcbf_nav.humanoid_config()
    assert hum["body_radius"] == 0.25 and hum["foot_clearance"] == 0.0
    c = Controller(hum)
    assert c.config == hum
    partial = Controller({"delta": 0.1, "capture_fraction": None})
    assert partial.config["delta"] == 0.1 and partial.config["capture_fraction"] is None
    assert partial.config["gamma"] == ldcbf_nav.default_config()["gamma"]


def test_first_step_is_optimal_and_well_shaped():
    for size in ("robot", "paper"):
        c = Controller(size=size)
        out = c.step(**START)
        assert out["status"] == "optimal" and out["input_error"] is None
        assert out["info"]["qp_status"] == "solved"
        assert out["foot_target"].shape == (2,)
        assert out["plan"]["states"].shape == (c.horizon, 5)
        assert out["plan"]["feet"].shape == (c.horizon, 2)
        assert out["plan"]["x0"].shape == (5,)
        # f_0 is the swing foot (the right one, the left is in stance).
        assert out["plan"]["first_side"] == "right"
        assert np.array_equal(out["plan"]["feet"][0], out["foot_target"])
        # Walking towards (10, 10): the planned CoM moves up and right.
        assert out["plan"]["states"][-1, 0] > 0 and out["plan"]["states"][-1, 1] > 0


def test_memory_and_reset():
    a, b = Controller(), Controller()
    first = a.step(**START)
    moved = dict(START, com_velocity=np.array([0.1, 0.05]), time_in_step=0.05)
    a1 = a.step(**moved)
    b1 = b.step(**moved)  # no memory of the first cycle
    assert a1["info"]["warm_started"] and not b1["info"]["warm_started"]
    a.reset()
    again = a.step(**START)
    assert again["foot_target"].tobytes() == first["foot_target"].tobytes()
    assert not again["info"]["warm_started"]


def test_sizes_agree_without_foot_rows():
    """The robot and paper sizes differ only by row capacity: without foot
    rows they solve the same QPs (same commands to rounding)."""
    r, p = Controller(size="robot"), Controller(size="paper")
    a, b = r.step(**START), p.step(**START)
    np.testing.assert_allclose(a["foot_target"], b["foot_target"], atol=1e-12)
    assert a["status"] == b["status"]
