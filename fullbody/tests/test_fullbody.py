"""The full-body loop end to end (short runs, headless) and its parts.

Asserted outcomes are deterministic counts and bounds of a MuJoCo run (same
inputs, same result), no timing."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from ldcbf_fullbody import cli, gait, model, plan, preview, robot, sim, walker


def test_swing_lands_on_a_target_that_moved():
    swing = gait.Swing(np.array([0.0, 0.0]), 0.1, 0.85)
    T, dt = 0.33, 0.002
    ticks = round(T / dt)
    for k in range(ticks):
        target = np.array([0.2, 0.1]) if k < ticks // 2 else np.array([0.25, 0.05])
        xy = swing.advance(target, k / ticks, dt, T)
    assert np.allclose(xy, [0.25, 0.05], atol=1e-9)


def test_derived_config_comes_from_the_model():
    cfg = robot.derived_config()
    assert 0.6 < cfg["com_height"] < 0.75
    assert cfg["foot_length"] == pytest.approx(0.18)
    assert cfg["foot_width"] == pytest.approx(0.07)
    # The arms stick out beyond the pelvis: the radius covers them.
    assert 0.2 < cfg["body_radius"] < 0.4
    assert cfg["step_duration"] == pytest.approx(0.4 * math.sqrt(cfg["com_height"]), abs=0.001)
    assert round(cfg["step_duration"] / 0.002, 9).is_integer()
    # The gait rows agree: a periodic sway within l_max reaches vy_min.
    cap = robot.lateral_velocity_cap(cfg["com_height"], cfg["step_duration"], cfg["l_max"])
    assert cap == pytest.approx(0.240, abs=0.001)
    assert cfg["vy_min"] < cap


def test_lip_with_the_g1_settings_reaches_circles_with_optimal_cycles():
    """The LIP plant with the derived settings (``lip circles``): the goal
    reached and no cycle's QP infeasible (vy_min 0.25 made every one)."""
    import ldcbf_nav

    summary = ldcbf_nav.simulate("circles", **cli.lip_overrides([]))["summary"]
    assert summary["reached_goal"]
    assert summary["status_counts"].get("infeasible", 0) == 0


def test_obstacles_are_prisms_touching_the_robot_only():
    square = np.array([[1.0, -0.5], [2.0, -0.5], [2.0, 0.5], [1.0, 0.5]])
    m = model.world([square], 1.5)
    import mujoco

    g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "obstacle0")
    assert m.geom_group[g] == model.OBSTACLE_GROUP
    assert m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 1
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    lo, hi = m.geom_aabb[g][:3] - m.geom_aabb[g][3:], m.geom_aabb[g][:3] + m.geom_aabb[g][3:]
    assert np.allclose(lo + d.geom_xpos[g], [1.0, -0.5, 0.0]) and np.allclose(hi + d.geom_xpos[g], [2.0, 0.5, 1.5])


def test_a_bad_set_names_the_key(tmp_path):
    with pytest.raises(ValueError, match="KEY=VALUE"):
        cli.split_sets(["delta"])
    code = cli.main(["run", "simple", "--set", "no_such_field=1", "--out", str(tmp_path / "x")])
    assert code == 2
    assert not (tmp_path / "x").exists()


def test_preview_tracks_a_zmp_step_and_holds_it():
    p = preview.Preview(0.635, 9.81, 0.01)
    p.reset(np.zeros(2))
    for k in range(400):
        t = (k + 1 + np.arange(p.n)) * 0.01
        p.advance(np.stack([np.where(t > 0.5, 0.1, 0.0), np.zeros_like(t)], 1))
    # 3.5 s after the step: on the new ZMP (the gains' tail makes it exact).
    assert p.x[0] == pytest.approx([0.1, 0.0], abs=1e-4)
    assert p.zmp() == pytest.approx([0.1, 0.0], abs=1e-4)


def test_zmp_reference_moves_in_double_support_then_stays_on_the_sole():
    chain = [np.array([0.0, 0.1]), np.array([0.1, -0.1]), np.array([0.2, 0.1])]
    z = walker.zmp_reference(np.array([0.0, 0.04, 0.1, 0.3 + 0.04, 0.3 + 0.2]), 0.0, 0.3, 0.08, np.array([0.0, -0.1]), chain)
    assert np.allclose(z[0], [0.0, -0.1])  # the step starts on the previous sole
    assert np.allclose(z[1], [0.0, 0.0])  # halfway through the double support
    assert np.allclose(z[2], [0.0, 0.1])  # single support on the stance sole
    assert np.allclose(z[3], [0.05, 0.0]) and np.allclose(z[4], [0.1, -0.1])
    # Beyond the plan the steps go on as the last ones did.
    assert np.allclose(walker.extend(chain + [np.array([0.3, -0.1])], 5)[4], [0.4, 0.1])


def test_hand_made_straight_plan_is_walked():
    """20 steps of 0.05 m with no controller (``walk-plan straight``): no
    fall, every foot within 3 cm of its footstep."""
    T = robot.derived_config()["step_duration"]
    result = plan.walk("straight", 20, 0.05, 0.0, T, sim.Options())
    assert result["falls"] == 0 and result["steps"] == 20
    assert result["landing_error_max_m"] <= 0.03


def test_short_walk_stays_up_and_clear(tmp_path):
    """10 simulated seconds of `simple` with the controller (the CI run): no
    fall, no link contact, footsteps landed within the bound, files written."""
    out = tmp_path / "simple"
    proc = subprocess.run(
        [sys.executable, "-m", "ldcbf_fullbody", "run", "simple", "--set", "time_limit=10.0", "--out", str(out), "--quiet"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["falls"] == 0
    assert summary["link_contacts"] == 0
    assert summary["steps"] >= 30
    # The footstep committed at 55 % of the step: the controller is not asked
    # after it, and the foot lands near the committed target (the issue's
    # 3 cm with a margin: measured 3.0 cm; 7 cm when the controller re-planned
    # to touchdown).
    assert summary["committed_cycles"] > 0
    assert summary["landing_error_p95_m"] <= 0.035
    assert (out / "steps.csv").read_text().count("\n") == summary["steps"] + 1
    assert (out / "run.png").stat().st_size > 10_000


def test_batch_seeds_and_shards_as_ldcbf_sim():
    from ldcbf_fullbody import batch

    assert batch.seed_range("0..5") == (0, 5)
    assert batch.seed_range("3..=4") == (3, 5)
    assert batch.seed_range("7") == (7, 8)
    for bad in ("5..5", "a..b", "-1..2"):
        with pytest.raises(ValueError, match="--seeds"):
            batch.seed_range(bad)
    assert batch.shard_seeds((10, 17), (2, 3)) == [11, 14]
    shards = [batch.shard_seeds((0, 10), (i, 3)) for i in (1, 2, 3)]
    assert sorted(s for part in shards for s in part) == list(range(10))
    with pytest.raises(ValueError, match="--shard"):
        batch.shard("4/3")


def test_a_crossed_swing_target_is_moved_out_to_the_minimum_width():
    stance = np.array([1.0, 2.0])
    # Heading +y: the left side is -x. A left-foot target 0.02 m to the right.
    target, moved = sim.separated(np.array([1.02, 2.1]), stance, math.pi / 2, "left", 0.12)
    assert moved and np.allclose(target, [0.88, 2.1])
    # Wide enough already, or the filter off: unchanged.
    wide = np.array([0.8, 2.1])
    assert sim.separated(wide, stance, math.pi / 2, "left", 0.12) == (wide, False)
    assert not sim.separated(np.array([1.02, 2.1]), stance, math.pi / 2, "left", 0.0)[1]
    # Right foot, heading 0: must be at y <= 1.88.
    target, moved = sim.separated(np.array([1.1, 1.95]), stance, 0.0, "right", 0.12)
    assert moved and np.allclose(target, [1.1, 1.88])
