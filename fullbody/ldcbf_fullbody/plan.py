"""Walking a hand-made footstep plan with no controller in the loop
(``python3 -m ldcbf_fullbody walk-plan KIND``): in place, a straight line, a
turn. It tells the body's walking apart from the controller's footsteps: a
body that cannot walk these cannot walk the controller's.

Frames and units: world W, m, rad, s; the body starts at the origin facing
+x, soles ``robot.STANCE_HALF_WIDTH`` either side, the left foot standing.
"""

import math
from typing import Any, Dict, List, Tuple

import numpy as np

from . import robot, sim, walker, wbc

#: Plan kinds and what they are.
KINDS = {
    "in-place": "stepping on the spot",
    "straight": "straight ahead, `stride` m per step",
    "turn": "along a circle, `stride` m and `turn` rad per step",
}


def footsteps(kind: str, count: int, stride: float, turn: float, half_width: float = robot.STANCE_HALF_WIDTH) -> List[Tuple[np.ndarray, float]]:
    """The plan: ``count`` steps (sole point (x, y), yaw) after the start, the
    right foot first. The path's point advances ``stride`` (m) and turns by
    ``turn`` (rad) each step (both 0 for ``in-place``); each sole is
    ``half_width`` to its side of the path, and the last two steps bring the
    feet side by side."""
    if kind not in KINDS:
        raise ValueError(f"walk-plan: unknown kind {kind!r} (one of {', '.join(KINDS)})")
    if kind == "in-place":
        stride, turn = 0.0, 0.0
    if kind == "straight":
        turn = 0.0
    out = []
    centre, heading = np.zeros(2), 0.0
    for k in range(count):
        if k < count - 1:
            heading += turn
            centre = centre + stride * np.array([math.cos(heading), math.sin(heading)])
        side = 1.0 if k % 2 == 1 else -1.0  # right first
        lateral = np.array([-math.sin(heading), math.cos(heading)])
        out.append((centre + side * half_width * lateral, heading))
    return out


def walk(kind: str, count: int, stride: float, turn: float, T: float, options: "sim.Options") -> Dict[str, Any]:
    """Walks the plan (``footsteps``) with step duration ``T`` (s) and the
    CoM height of the derived configuration; returns a summary: falls, steps
    landed, landing errors (m), the largest foot slip of a stance foot (m)
    and the sim time (s)."""
    H = robot.posture_com_height()
    plan = footsteps(kind, count, stride, turn)
    body = sim.Body([], 1.0)
    ik = wbc.WholeBodyIK(body.m.opt.timestep)
    hw = robot.STANCE_HALF_WIDTH
    soles = {"left": np.array([0.0, hw]), "right": np.array([0.0, -hw])}
    yaws = {"left": 0.0, "right": 0.0}
    q = ik.settle(wbc.foot_pose([*soles["left"], 0.0], 0.0), wbc.foot_pose([*soles["right"], 0.0], 0.0), [0.0, 0.0, H], 0.0)
    body.set_pose(ik.robot.get_T_world_fbase(), q)
    w = walker.Walker(body, ik, options, H, 9.81, T, "left", soles, yaws)
    sim.shift_weight(w, options)
    errors: List[float] = []
    fell = False
    k = 0
    while k < len(plan):
        target, yaw = plan[k]
        future = [p for p, _ in plan[k + 1 : k + 4]]
        landing = w.tick(target, yaw, future, yaw)
        if body.fallen():
            fell = True
            break
        if landing is not None:
            errors.append(float(np.linalg.norm(landing.sole[:2] - target)))
            k += 1
    # Standing still after the plan, to see it come to rest.
    for _ in range(round(1.0 / w.dt)):
        if fell:
            break
        w.stand(w.com_ref + 0.02 * ((w.soles["left"] + w.soles["right"]) / 2.0 - w.com_ref), plan[-1][1], 0.5)
        fell = body.fallen()
    e = np.array(errors) if errors else np.zeros(1)
    return {
        "kind": kind,
        "falls": int(fell),
        "steps": len(errors),
        "planned_steps": len(plan),
        "landing_error_p95_m": float(np.percentile(e, 95)),
        "landing_error_max_m": float(e.max()),
        "sim_time": body.d.time,
        "ik_soft_feet_ticks": ik.soft_ticks,
    }
