"""The controller's configuration derived from the G1 model (docs/fullbody.md,
"Configuration"): CoM height, footprint, body radius, and the gait limits of
the paper's Table I scaled to that CoM height.

Units: m, s, rad; frames: the model's (x forward, z up).
"""

import math
from typing import Dict

import mujoco
import numpy as np

from . import model, wbc

#: CoM height of the paper's Table I (the controller's defaults), m.
TABLE_I_COM_HEIGHT = 1.0
#: The step duration is rounded to this (s): a whole number of MuJoCo ticks
#: (2 ms) and of the LIP plant's (1 ms).
STEP_QUANTUM = 0.002
#: Lowest lateral velocity at a step's end (times the stance sign), m/s: not
#: scaled from Table I (0.08 m/s) but raised, so that the LIP's sway puts the
#: feet wide enough apart for the G1's hips, and kept below
#: :func:`lateral_velocity_cap` (0.240 m/s), the most a periodic gait within
#: ``l_max`` can have. Measured (docs/fullbody.md): 0.08 put the swing foot
#: 1 cm beside the stance foot and the body fell at 1.75 s; 0.25, above the
#: cap, made every cycle's QP infeasible and the plan's strides about 1 cm
#: (no goal reached in 40 s); 0.2 (a periodic step width of at least
#: 0.183 m) leaves every LIP cycle optimal.
VY_MIN = 0.2
#: Lowest forward velocity at a step's end, m/s: not scaled from Table I
#: (-0.08 m/s at the G1's H) but 0, no step that ends walking backwards.
#: Measured (docs/fullbody.md): beside an obstacle the plan's feet went
#: 0.15 to 0.28 m forwards and back on alternate steps and the body fell
#: (`circles` with the planner at 73.4 s); with 0 it reached the goal.
VX_MIN = 0.0
#: The LDCBF margin ``delta`` (m): the body's CoM is not the LIP's (landing
#: errors p95 about 8 cm), and the collision boxes of the hands swing outside
#: the standing body's disk. With 0 the right wrist touched a pillar of
#: `circles` and the body fell at 69.3 s (docs/fullbody.md).
DELTA = 0.05
#: Highest forward velocity at a step's end, m/s: not scaled from Table I
#: (0.637 m/s at the G1's H) but what the body walks. Measured with no
#: controller (``walk-plan straight``, docs/fullbody.md): 40 steps of 0.05 m
#: (0.16 m/s) walked, 0.075 m (0.24 m/s) fell after 11 steps; in the loop,
#: 0.2 walked 40 s of `simple`, `circles` and `paper` without a fall, 0.3
#: fell on `circles`, the scaled value on all three.
VX_MAX = 0.2
#: Half the lateral distance between the sole points when standing, m.
STANCE_HALF_WIDTH = 0.1
#: The ankle-roll link's collision spheres (centre x, y in the link frame, m) and radius.
FOOT_SPHERE_X = (-0.05, 0.12)
FOOT_SPHERE_Y = (-0.03, 0.03)
FOOT_SPHERE_RADIUS = 0.005


def standing(H: float) -> Dict[str, float]:
    """Joint angles (rad) of the G1 standing with its CoM at height ``H`` (m)
    above the soles, the soles at ``±STANCE_HALF_WIDTH``."""
    ik = wbc.WholeBodyIK(0.01)
    return ik.settle(
        wbc.foot_pose([0.0, STANCE_HALF_WIDTH, 0.0], 0.0),
        wbc.foot_pose([0.0, -STANCE_HALF_WIDTH, 0.0], 0.0),
        [0.0, 0.0, H],
        0.0,
    )


def posture_com_height() -> float:
    """The CoM's height above the soles (m) in the posture ``wbc.POSTURE``
    (knees bent 0.6 rad, hips and ankles -0.3 rad), feet flat."""
    ik = wbc.WholeBodyIK(0.01)
    robot = ik.robot
    sole = robot.get_T_world_frame(wbc.FOOT_FRAME["left"]) @ np.append(wbc.SOLE_OFFSET, 1.0)
    return float(robot.com_world()[2] - sole[2])


def body_radius(H: float) -> float:
    """Largest horizontal distance (m) from the CoM to any collision box of the
    body, feet excluded (the controller's foot rows keep the feet clear),
    standing at CoM height ``H``: every corner of every box counted."""
    m = model.world([], 1.0)
    d = mujoco.MjData(m)
    q = standing(H)
    for j in range(m.njnt):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
        if name in q:
            d.qpos[m.jnt_qposadr[j]] = q[name]
    d.qpos[2] = 1.0
    d.qpos[3] = 1.0
    mujoco.mj_forward(m, d)
    com = d.subtree_com[1][:2]
    worst = 0.0
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    for g in range(m.ngeom):
        body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, m.geom_bodyid[g]) or ""
        if m.geom_bodyid[g] == 0 or "ankle" in body:
            continue
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
            half = m.geom_size[g]
        else:
            half = np.full(3, m.geom_rbound[g])
        corners = d.geom_xpos[g] + (signs * half) @ d.geom_xmat[g].reshape(3, 3).T
        worst = max(worst, float(np.max(np.linalg.norm(corners[:, :2] - com, axis=1))))
    return worst


def lateral_velocity_cap(H: float, T: float, l_max: float, gravity: float = 9.81) -> float:
    """The largest ``vy_min`` (m/s) a periodic gait meets with every foot
    within ``l_max`` of the CoM (laterally, at the step's start): in the
    LIP's symmetric sway the CoM starts a step ``e`` inside the stance foot
    and moving towards it at ``beta e tanh(beta T / 2)``, and ends it moving
    away at that speed (``beta = sqrt(g / H)``); ``e <= l_max`` bounds it.
    Above it the gait rows (``VelLatLower`` with ``ReachLat*``) contradict
    each other in steady walking and every QP is infeasible."""
    beta = math.sqrt(gravity / H)
    return beta * l_max * math.tanh(beta * T / 2.0)


def derived_config() -> Dict[str, float]:
    """The controller settings taken from the model (names of
    ``ldcbf_nav.CONFIG_FIELDS``): ``com_height`` the CoM height of the
    standing posture; ``foot_length`` x ``foot_width`` the rectangle around
    the four foot spheres; ``body_radius`` as :func:`body_radius`; the gait
    limits of Table I (defined for a 1 m CoM height) scaled to ``H`` by
    Froude similarity (lengths times ``H``, times and velocities times
    ``sqrt(H)``, rates over ``sqrt(H)``; ``T`` rounded to ``STEP_QUANTUM``), which maps a LIP gait of one height
    to the same dimensionless gait of the other; except ``vy_min`` and
    ``vx_max`` and ``vx_min``, set to ``VY_MIN``, ``VX_MAX`` and ``VX_MIN`` (``VY_MIN`` below
    :func:`lateral_velocity_cap`), and ``delta`` (``DELTA``), the LDCBF
    margin for the body's tracking error."""
    import ldcbf_nav

    table = ldcbf_nav.default_config()
    H = posture_com_height()
    r = H / TABLE_I_COM_HEIGHT
    out = {
        "com_height": H,
        "step_duration": round(table["step_duration"] * math.sqrt(r) / STEP_QUANTUM) * STEP_QUANTUM,
        "l_max": table["l_max"] * r,
        "alpha": table["alpha"] * r,
        "omega_max": table["omega_max"] / math.sqrt(r),
        "foot_length": FOOT_SPHERE_X[1] - FOOT_SPHERE_X[0] + 2.0 * FOOT_SPHERE_RADIUS,
        "foot_width": FOOT_SPHERE_Y[1] - FOOT_SPHERE_Y[0] + 2.0 * FOOT_SPHERE_RADIUS,
        "body_radius": body_radius(H),
    }
    for key in ("vx_min", "vx_max", "vy_min", "vy_max"):
        out[key] = table[key] * math.sqrt(r)
    out["vy_min"] = VY_MIN
    out["vx_max"] = VX_MAX
    out["vx_min"] = VX_MIN
    out["delta"] = DELTA
    assert out["vy_min"] < lateral_velocity_cap(H, out["step_duration"], out["l_max"]), "vy_min above what l_max allows"
    return out
