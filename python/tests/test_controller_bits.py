"""`ldcbf_nav.Controller` against the Rust controller on recorded cycles, bit for bit.

The cycles are recorded by the CLI (`ldcbf-sim run NAME --trajectory-every 1`,
a separate Rust build): every control cycle's input is in its logs (as
`ldcbf_sim::studies::replay` rebuilds it: the 1 kHz sample of the call's tick for the
CoM state, heading, turning rate and stance side; the last footstep landed for
the stance foot; the tick in the step for the time in step; the scenario's
goal and map), and its output is in `cycles.csv`. The same inputs through a
fresh Python `Controller` with the scenario's configuration, in order (the
controller's warm start carries over between cycles), must give the same
outputs, bit for bit.
"""

from __future__ import annotations

import pytest

import ldcbf_nav

DT = 1e-3  # the plant tick, s (ldcbf_sim::sim::PLANT_DT)


def bits(x: float) -> str:
    return float(x).hex()


# A point robot without foot rows: the CLI's controller (RobotController) then
# solves the QPs of PaperController, whose only difference is the row capacity.
POINT = {
    "robot.body_radius": 0,
    "robot.foot_length": 0,
    "robot.foot_width": 0,
    "robot.keep_feet_clear": False,
}


# A 0.6 m/s push to the left at 3 s: the walk cannot recover (it ends as
# diverged), and on the way the controller relaxes the gait rows, then the
# safety rows, and finally holds on an out-of-range state.
PUSH = {"disturbance.push_time": 3.0, "disturbance.push_lateral": 0.6}


@pytest.mark.parametrize(
    "name, size, sets, sources",
    [
        ("paper", "robot", {}, {"optimal"}),
        ("simple", "robot", {}, {"optimal"}),
        ("paper", "paper", POINT, {"optimal"}),
        ("paper", "robot", PUSH, {"optimal", "relaxed_gait", "relaxed_safety", "hold"}),
    ],
    ids=["paper", "simple", "paper-point-paper-size", "paper-push"],
)
def test_replayed_cycles_match_the_rust_controller(name, size, sets, sources, cli_runs, in_repo):
    args = [a for k, v in sets.items() for a in ("--set", f"{k}={str(v).lower()}")]
    cli = cli_runs(name, "--trajectory-every", "1", *args)
    sc = ldcbf_nav.load_scenario(name, **sets)
    assert sc["planner"] == "none", "the goal of every cycle is the scenario's"
    if size == "paper":
        assert sc["config"]["foot_clearance"] is None
    ctl = ldcbf_nav.Controller(sc["config"], size=size)
    tr, fs, cy = cli.trajectory, cli.footsteps, cli.cycles
    foot_ticks = [round(float(t) / DT) for t in fs["t"]]
    n = len(cy["t"])
    seen = set()
    for k in range(n):
        tick = round(float(cy["t"][k]) / DT)
        assert round(float(tr["t"][tick]) / DT) == tick  # one sample per tick
        j = max(i for i, ft in enumerate(foot_ticks) if ft <= tick)
        out = ctl.step(
            com_position=[float(tr["px"][tick]), float(tr["py"][tick])],
            com_velocity=[float(tr["vx"][tick]), float(tr["vy"][tick])],
            heading=float(tr["theta"][tick]),
            turning_rate=float(tr["omega"][tick]),
            stance_foot=[float(fs["x"][j]), float(fs["y"][j])],
            stance_side=tr["stance"][tick],
            time_in_step=round(float(cy["time_in_step"][k]) / DT) * DT,
            goal=sc["goal"],
            obstacles=sc["obstacles"],
        )
        info = out["info"]
        x0 = out["plan"]["x0"]
        got = {
            "foot_x": out["foot_target"][0],
            "foot_y": out["foot_target"][1],
            "omega": out["turning_rate"],
            "x0_px": x0[0],
            "x0_py": x0[1],
            "x0_vx": x0[2],
            "x0_vy": x0[3],
            "x0_theta": x0[4],
            "cost": info["cost"],
            "max_violation": info["max_violation"],
            "min_h0": info["min_h0"],
            "relax_gait": info["relax_gait"],
            "relax_safety": info["relax_safety"],
            "relax_capture": info["relax_capture"],
        }
        for col, v in got.items():
            assert bits(v) == bits(float(cy[col][k])), (
                f"cycle {k} (t = {cy['t'][k]}): {col} = {v!r}, the Rust controller's {cy[col][k]}"
            )
        assert out["status"] == cy["status"][k], f"cycle {k}"
        assert info["source"] == cy["source"][k], f"cycle {k}"
        assert info["iterations"] == int(cy["iterations"][k]), f"cycle {k}"
        assert info["active_set_size"] == int(cy["active_set"][k]), f"cycle {k}"
        assert info["active_obstacles"] == int(cy["active_obstacles"][k]), f"cycle {k}"
        assert int(info["obstacles_truncated"]) == int(cy["truncated"][k]), f"cycle {k}"
        seen.add(info["source"])
    assert n > 100, f"{name}: only {n} cycles recorded"
    assert sources <= seen, f"command sources replayed: {seen}"
