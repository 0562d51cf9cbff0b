"""The full-body closed loop: the G1 in MuJoCo, our controller (``ldcbf_nav``)
at 20 Hz on the measured state, placo's IK at the physics rate.

Per physics tick (``dt`` = 2 ms): the gait references (``gait.py``) give both
feet's poses and the CoM; the IK (``wbc.py``) turns them into joint targets;
MuJoCo's position servos track them; link-obstacle contacts are counted.
Every ``control_period`` the controller is given the *measured* CoM position
and velocity (MuJoCo's whole-body CoM), the pelvis heading, the turning rate
in force, the measured stance sole point, the time in the step, the goal and
the obstacles, and returns the swing foot's target and the next turning rate.

A step lasts the controller's ``T``; at its end the support changes sides
(as in the LIP plant), and the landed foot's measured sole point becomes the
stance foot. A fall ends the run: the pelvis below ``FALL_HEIGHT`` or the
torso tilted more than ``FALL_TILT`` from upright.
"""

import dataclasses
import math
import time
from typing import Any, Dict, List, Optional, Sequence

import mujoco
import numpy as np

from . import gait, model, wbc

#: A fall: the pelvis origin below this height (m; standing: 0.714 m) ...
FALL_HEIGHT = 0.45
#: ... or the torso's z axis more than this from the vertical (rad; 45 deg).
FALL_TILT = math.radians(45.0)


@dataclasses.dataclass
class Options:
    """Settings of a full-body run (``--set`` keys without a controller name)."""

    #: Height of the obstacles' prisms, m.
    obstacle_height: float = 1.5
    #: Swing foot apex above the ground, m.
    swing_height: float = 0.06
    #: Controller period, s (20 Hz).
    control_period: float = 0.05
    #: Fraction of the gap between the measured CoM state and the LIP
    #: reference closed at each control cycle (1: restart the reference at
    #: the measurement).
    reference_reset: float = 0.3
    #: CoM feedback gain of the IK's CoM target: ``ref + gain (ref - measured)``
    #: in the horizontal plane (0: open loop).
    com_feedback: float = 1.0
    #: DCM feedback gain of the IK's CoM target: ``+ gain (xi_ref - xi)`` with
    #: the divergent component ``xi = c + c' / beta`` of the reference and of
    #: the measurement, horizontal (0: none).
    dcm_feedback: float = 0.0
    #: Add the static gravity torques of the IK configuration (placo, on the
    #: stance foot) to the servos as a feed-forward.
    gravity_feedforward: bool = True
    #: Swing-foot feedback gain: the IK's swing target is ``path + gain (path -
    #: measured)`` in the horizontal plane (0: open loop).
    swing_feedback: float = 1.0
    #: The swing foot follows the controller's target until this fraction of
    #: the step, then holds the last one (committed) to touchdown (1: never
    #: frozen; the path itself ends at ``gait.SWING_END``).
    swing_freeze: float = 1.0
    #: After a touchdown the new swing foot holds still until the next
    #: control cycle plans it (False: it heads for the last target, which was
    #: planned for the other foot).
    hold_until_planned: bool = False
    #: Smallest lateral distance (m) between the sole points, along the stance
    #: foot's lateral axis: a controller target closer to (or across) the
    #: stance foot is moved out to it (0: off). The controller has no such
    #: row; the G1's legs cannot put the feet side by side.
    min_foot_width: float = 0.0
    #: The IK's stance foot is the measured stance foot (True) or where it
    #: landed (False).
    anchor_stance: bool = False
    #: MuJoCo's ``impratio`` with elliptic friction cones (0: MuJoCo's default
    #: pyramidal cones, impratio 1). Above 1 it makes friction harder, so the
    #: stance foot creeps less under the swing leg's reaction (MuJoCo's
    #: documentation recommends it against slip).
    impratio: float = 0.0
    #: Frames per simulated second of an animation (0: none). Needs
    #: offscreen OpenGL (``MUJOCO_GL=egl``).
    animation_fps: float = 0.0
    #: Simulated time limit, s (``None``: the scenario's ``time_limit``).
    time_limit: Optional[float] = None
    #: Before the first step, the CoM moves (in double support, quasi-statically)
    #: from between the soles towards the stance sole by this fraction of
    #: the distance (1: over the stance sole, the LIP plant's start) ...
    initial_shift: float = 0.8
    #: ... over this time, s.
    settle_time: float = 1.0


@dataclasses.dataclass
class StepRecord:
    """One landed footstep (W, m, s)."""

    index: int
    time: float
    side: str
    planned_x: float
    planned_y: float
    #: The controller's last target before touchdown (differs from the
    #: planned, committed one when it changed after ``swing_freeze``).
    latest_x: float
    latest_y: float
    #: Where the swing path ended (the IK's last horizontal target).
    swing_end_x: float
    swing_end_y: float
    landed_x: float
    landed_y: float
    landed_yaw: float
    error: float
    com_x: float
    com_y: float
    status: str


def yaw_of(R: np.ndarray) -> float:
    """Heading (rad) of a rotation matrix's x axis in the ground plane."""
    return math.atan2(R[1, 0], R[0, 0])


class Body:
    """The G1 in its MuJoCo world and what is measured on it."""

    def __init__(self, obstacles: Sequence[np.ndarray], height: float) -> None:
        self.m = model.world(obstacles, height)
        self.d = mujoco.MjData(self.m)
        m = self.m
        self.pelvis = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "pelvis")
        self.torso = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "torso_link")
        self.foot_body = {s: mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f) for s, f in wbc.FOOT_FRAME.items()}
        self.obstacle_geoms = [g for g in range(m.ngeom) if m.geom_group[g] == model.OBSTACLE_GROUP]
        self.robot_geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] != 0]
        self.is_obstacle = np.zeros(m.ngeom, dtype=bool)
        self.is_obstacle[self.obstacle_geoms] = True
        self.actuated = [m.jnt_qposadr[m.actuator_trnid[a, 0]] for a in range(m.nu)]
        self.actuator_names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(m.nu)]
        self.link_names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(m.nbody)]
        self.kp = m.actuator_gainprm[:, 0].copy()
        # Targets may leave the joint range by the feed-forward offset.
        m.actuator_ctrllimited[:] = 0

    def set_pose(self, base: np.ndarray, q: Dict[str, float]) -> None:
        """Places the body: floating base pose (4x4, W) and joint angles (rad)."""
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, base[:3, :3].flatten())
        self.d.qpos[:3] = base[:3, 3]
        self.d.qpos[3:7] = quat
        self.d.qvel[:] = 0.0
        for a, adr in enumerate(self.actuated):
            self.d.qpos[adr] = q[self.actuator_names[a]]
        self.command(q)
        mujoco.mj_forward(self.m, self.d)

    def command(self, q: Dict[str, float], torque: Optional[Dict[str, float]] = None) -> None:
        """Joint position targets (rad) and feed-forward torques (N m) by joint
        name: a position servo's force is ``kp (ctrl - q)``, so the target is
        offset by ``torque / kp`` (the servo's torque limit still applies)."""
        for a, name in enumerate(self.actuator_names):
            extra = torque[name] / self.kp[a] if torque else 0.0
            self.d.ctrl[a] = q[name] + extra

    def com(self) -> np.ndarray:
        """Whole-body CoM (m, W)."""
        return self.d.subtree_com[self.pelvis].copy()

    def com_velocity(self) -> np.ndarray:
        """Whole-body CoM velocity (m/s, W)."""
        mujoco.mj_subtreeVel(self.m, self.d)
        return self.d.subtree_linvel[self.pelvis].copy()

    def heading(self) -> float:
        """The pelvis's heading (rad)."""
        return yaw_of(self.d.xmat[self.pelvis].reshape(3, 3))

    def sole(self, side: str) -> np.ndarray:
        """The sole point of a foot (m, W)."""
        b = self.foot_body[side]
        return self.d.xpos[b] + self.d.xmat[b].reshape(3, 3) @ wbc.SOLE_OFFSET

    def foot_yaw(self, side: str) -> float:
        """A foot's heading (rad)."""
        return yaw_of(self.d.xmat[self.foot_body[side]].reshape(3, 3))

    def fallen(self) -> bool:
        """Pelvis too low or torso tilted too far (``FALL_HEIGHT``, ``FALL_TILT``)."""
        tilt = math.acos(min(1.0, max(-1.0, self.d.xmat[self.torso][8])))
        return self.d.xpos[self.pelvis][2] < FALL_HEIGHT or tilt > FALL_TILT

    def obstacle_contacts(self) -> List[str]:
        """Names of the links touching an obstacle now."""
        links = []
        for c in self.d.contact[: self.d.ncon]:
            g1, g2 = c.geom1, c.geom2
            if self.is_obstacle[g1] != self.is_obstacle[g2]:
                g = g2 if self.is_obstacle[g1] else g1
                links.append(self.link_names[self.m.geom_bodyid[g]])
        return links

    def clearance(self, near: float = 1.0) -> float:
        """Smallest distance (m) between a robot collision geom and an
        obstacle, among pairs closer than ``near`` (``inf`` if none)."""
        best = math.inf
        fromto = np.zeros(6)
        for o in self.obstacle_geoms:
            for g in self.robot_geoms:
                dist = mujoco.mj_geomDistance(self.m, self.d, g, o, near, fromto)
                best = min(best, dist)
        return best


def separated(target: np.ndarray, stance: np.ndarray, stance_yaw: float, swing: str, width: float):
    """The swing target (x, y, W) moved sideways, if needed, so that it lies at
    least ``width`` (m) to the swing's side of the stance sole point along the
    stance foot's lateral axis (no crossed or touching feet); returns the
    target and whether it was moved."""
    lateral = np.array([-math.sin(stance_yaw), math.cos(stance_yaw)]) * (1.0 if swing == "left" else -1.0)
    gap = float((target - stance) @ lateral)
    if width <= 0.0 or gap >= width:
        return target, False
    return target + (width - gap) * lateral, True


def drive(
    body: Body,
    ik: wbc.WholeBodyIK,
    options: Options,
    left: np.ndarray,
    right: np.ndarray,
    com: np.ndarray,
    yaw: float,
    left_share: float,
    com_velocity: Optional[np.ndarray] = None,
    beta: float = 1.0,
) -> None:
    """One physics tick: the IK on the references (foot poses 4x4, CoM
    reference (x, y, z), trunk yaw), the CoM feedback, the servos' targets
    and feed-forward, then the MuJoCo step."""
    measured = body.com()
    target = np.array(com, dtype=float)
    target[:2] += options.com_feedback * (target[:2] - measured[:2])
    if options.dcm_feedback and com_velocity is not None:
        xi_ref = com[:2] + com_velocity / beta
        xi = measured[:2] + body.com_velocity()[:2] / beta
        target[:2] += options.dcm_feedback * (xi_ref - xi)
    ik.place(left, right, target, yaw)
    q = ik.solve(1)
    body.command(q, ik.gravity_torques(left_share) if options.gravity_feedforward else None)
    mujoco.mj_step(body.m, body.d)


def run(scenario: Dict[str, Any], config: Dict[str, Any], options: Options, log=None, trace=None) -> Dict[str, Any]:
    """Walks ``scenario`` (``ldcbf_nav.load_scenario``'s dict) with the
    controller configured by ``config``; returns the summary, the per-step
    records and the sampled paths (see ``report.py``)."""
    import ldcbf_nav

    ctl = ldcbf_nav.Controller(config)
    obstacles = [np.asarray(p, dtype=float) for p in scenario["obstacles"]]
    body = Body(obstacles, options.obstacle_height)
    m, d = body.m, body.d
    if options.impratio > 0:
        m.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        m.opt.impratio = options.impratio
    dt = m.opt.timestep
    H = config["com_height"]
    T = config["step_duration"]
    beta = math.sqrt(config["gravity"] / H)
    per_control = max(1, round(options.control_period / dt))
    per_step = round(T / dt)
    goal = np.asarray(scenario["goal"], dtype=float)
    time_limit = options.time_limit if options.time_limit is not None else scenario["time_limit"]

    # Start: standing in double support, CoM over the midpoint of the soles.
    start = np.asarray(scenario["start"], dtype=float)
    heading = float(scenario["start_heading"])
    stance = scenario["stance"]
    R = wbc.yaw_matrix(heading)
    left = np.array([*start, 0.0]) + R @ [0.0, 0.1, 0.0]
    right = np.array([*start, 0.0]) + R @ [0.0, -0.1, 0.0]
    soles = {"left": left, "right": right}
    yaws = {"left": heading, "right": heading}
    ik = wbc.WholeBodyIK(dt)
    q = ik.settle(wbc.foot_pose(left, heading), wbc.foot_pose(right, heading), [*start, H], heading)
    body.set_pose(ik.robot.get_T_world_fbase(), q)
    mid = np.array([*start, H])
    shifted = mid + options.initial_shift * (np.array([*soles[stance][:2], H]) - mid)
    settle_ticks = max(1, round(options.settle_time / dt))
    for k in range(settle_ticks):
        s = gait.smoothstep((k + 1) / settle_ticks)
        share = 0.5 + 0.5 * options.initial_shift * s * (1.0 if stance == "left" else -1.0)
        drive(body, ik, options, wbc.foot_pose(left, heading), wbc.foot_pose(right, heading), mid + s * (shifted - mid), heading, share)

    com = body.com()
    p_ref, v_ref = com[:2].copy(), np.zeros(2)
    swing = "right" if stance == "left" else "left"
    swing_path = gait.Swing(soles[swing][:2])
    target = soles[swing][:2].copy()
    latest = target.copy()
    omega = 0.0
    heading_ref = heading
    stance_sole = soles[stance][:2].copy()
    tick_in_step = 0
    steps: List[StepRecord] = []
    contacts: Dict[str, int] = {}
    first_contact: Optional[float] = None
    min_clear = math.inf
    samples: Dict[str, List[Any]] = {"t": [], "com": [], "left": [], "right": [], "links": []}
    tracked = ["pelvis", "torso_link", "left_wrist_yaw_link", "right_wrist_yaw_link", "left_knee_link", "right_knee_link"]
    tracked_ids = [body.link_names.index(n) for n in tracked]
    frames: List[np.ndarray] = []
    renderer = None
    per_frame = 0
    if options.animation_fps > 0:
        renderer = mujoco.Renderer(m, 240, 320)
        camera = mujoco.MjvCamera()
        camera.distance, camera.elevation, camera.azimuth = 3.0, -30.0, 225.0
        per_frame = max(1, round(1.0 / (options.animation_fps * dt)))
    reached = False
    fell = False
    status_counts: Dict[str, int] = {}
    widened = 0
    t0 = time.perf_counter()
    t = 0.0
    tick = 0
    last_status = ""
    max_ticks = round(time_limit / dt)
    while tick < max_ticks:
        if tick % per_control == 0:
            com = body.com()
            vel = body.com_velocity()
            out = ctl.step(
                com_position=com[:2],
                com_velocity=vel[:2],
                heading=body.heading(),
                turning_rate=omega,
                stance_foot=stance_sole,
                stance_side=stance,
                time_in_step=tick_in_step * dt,
                goal=goal,
                obstacles=obstacles,
            )
            last_status = out["status"]
            status_counts[last_status] = status_counts.get(last_status, 0) + 1
            latest = np.asarray(out["foot_target"], dtype=float)
            if tick_in_step < options.swing_freeze * per_step:
                target, moved = separated(latest, stance_sole, yaws[stance], swing, options.min_foot_width)
                widened += int(moved)
            if trace:
                trace(
                    f"t={t:6.3f} com {com.round(3)} v {vel[:2].round(2)} ref {p_ref.round(3)} "
                    f"stance {stance} {stance_sole.round(3)} target {target.round(3)} swing {body.sole(swing).round(3)}"
                )
            next_omega = float(out["turning_rate"])
            a = options.reference_reset
            p_ref = p_ref + a * (com[:2] - p_ref)
            v_ref = v_ref + a * (vel[:2] - v_ref)
            samples["t"].append(t)
            samples["com"].append(com.copy())
            samples["left"].append(body.sole("left").copy())
            samples["right"].append(body.sole("right").copy())
            samples["links"].append(d.xpos[tracked_ids].copy())
            if np.linalg.norm(com[:2] - goal) <= scenario["success_radius"]:
                reached = True
                break
            min_clear = min(min_clear, body.clearance())
        phase = tick_in_step / per_step
        # The heading integrates the turning rate in force (as in the LIP plant).
        heading_ref += omega * dt
        p_ref, v_ref = gait.lip_flow(p_ref, v_ref, stance_sole, beta, dt)
        xy = swing_path.advance(target, phase, dt, T)
        xy = xy + options.swing_feedback * (xy - body.sole(swing)[:2])
        swing_xyz = np.array([xy[0], xy[1], gait.swing_height((tick_in_step + 1) / per_step, options.swing_height)])
        land_yaw = yaws[swing] + (heading_ref + omega * (T - (tick_in_step + 1) * dt) - yaws[swing]) * gait.smoothstep(phase)
        # The IK's stance foot is where the body's stance foot is (flat on
        # the ground), so that the swing foot is placed in the world's frame.
        if options.anchor_stance:
            stance_pose = wbc.foot_pose([*body.sole(stance)[:2], 0.0], body.foot_yaw(stance))
        else:
            stance_pose = wbc.foot_pose([*stance_sole, 0.0], yaws[stance])
        swing_pose = wbc.foot_pose(swing_xyz, land_yaw)
        left_pose, right_pose = (stance_pose, swing_pose) if stance == "left" else (swing_pose, stance_pose)
        drive(body, ik, options, left_pose, right_pose, np.array([p_ref[0], p_ref[1], H]), heading_ref, 1.0 if stance == "left" else 0.0, v_ref, beta)
        tick += 1
        t = tick * dt
        if renderer is not None and tick % per_frame == 0:
            camera.lookat[:] = body.com()
            renderer.update_scene(d, camera)
            frames.append(renderer.render().copy())
        tick_in_step += 1
        for link in body.obstacle_contacts():
            contacts[link] = contacts.get(link, 0) + 1
            if first_contact is None:
                first_contact = t
        if body.fallen():
            fell = True
            break
        if tick_in_step >= per_step:
            landed = body.sole(swing)
            err = float(np.linalg.norm(landed[:2] - target))
            com = body.com()
            steps.append(
                StepRecord(len(steps) + 1, t, swing, target[0], target[1], latest[0], latest[1], swing_path.x[0], swing_path.x[1], landed[0], landed[1], body.foot_yaw(swing), err, com[0], com[1], last_status)
            )
            if log:
                log(
                    f"t={t:6.2f} step {len(steps):3d} {swing:5s} error {err * 100:5.1f} cm "
                    f"target ({target[0]:.3f}, {target[1]:.3f}) landed ({landed[0]:.3f}, {landed[1]:.3f}) "
                    f"com ({com[0]:.2f}, {com[1]:.2f})"
                )
            yaws[swing] = land_yaw
            stance, swing = swing, stance
            stance_sole = landed[:2].copy()
            swing_path = gait.Swing(body.sole(swing)[:2])
            if options.hold_until_planned:
                # Until the controller plans this step, the new swing foot
                # holds where it is (the last target was the other foot's).
                target = swing_path.x.copy()
                latest = target.copy()
            tick_in_step = 0
            omega = next_omega
    wall = time.perf_counter() - t0
    errors = np.array([s.error for s in steps]) if steps else np.zeros(0)
    summary = {
        "scenario": scenario["name"],
        "reached_goal": bool(reached),
        "falls": int(fell),
        "link_contacts": int(sum(contacts.values())),
        "contact_links": contacts,
        "first_contact_time": first_contact,
        "landing_error_p95_m": float(np.percentile(errors, 95)) if errors.size else None,
        "landing_error_max_m": float(errors.max()) if errors.size else None,
        "min_clearance_3d_m": float(min_clear) if math.isfinite(min_clear) else None,
        "steps": len(steps),
        "sim_time": t,
        "wall_time": wall,
        "real_time_factor": t / wall if wall > 0 else None,
        "controller_status": status_counts,
        "ik_soft_feet_ticks": ik.soft_ticks,
        "widened_targets": widened,
        "physics_dt": dt,
    }
    return {"frames": frames, "summary": summary, "steps": steps, "samples": samples, "tracked": tracked, "obstacles": obstacles, "goal": goal, "start": start}
