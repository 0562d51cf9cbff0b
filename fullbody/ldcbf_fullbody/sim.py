"""The full-body closed loop: the G1 in MuJoCo, our controller (``ldcbf_nav``)
at 20 Hz on the measured state, placo's IK at the physics rate.

Per physics tick (``dt`` = 2 ms): the walker (``walker.py``: the ZMP preview
CoM, the swing path, foot damping) gives both feet's poses and the CoM; the
IK (``wbc.py``) turns them into joint targets; MuJoCo's position servos track
them; link-obstacle contacts are counted.
Every ``control_period`` until the step's ``commit`` fraction the controller
is given the *measured* CoM position and velocity (MuJoCo's whole-body CoM),
the pelvis heading, the turning rate in force, the measured stance sole
point, the time in the step, the goal and the obstacles, and returns the
swing foot's target and the next turning rate; after it, to touchdown, the
step is committed: the controller is not asked and its last target stands.

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

from . import gait, model, robot, walker, wbc

#: A fall: the pelvis origin below this height (m; standing: 0.714 m) ...
FALL_HEIGHT = 0.45
#: ... or the torso's z axis more than this from the vertical (rad; 45 deg).
FALL_TILT = math.radians(45.0)


@dataclasses.dataclass
class Options(walker.Gait):
    """Settings of a full-body run (``--set`` keys without a controller name);
    the walking pattern's are ``walker.Gait``'s."""

    #: Height of the obstacles' prisms, m.
    obstacle_height: float = 1.5
    #: Controller period, s (20 Hz).
    control_period: float = 0.05
    #: The footstep is committed at this fraction of the step: from then to
    #: touchdown the controller is not asked (its last ``foot_target`` is the
    #: step's target, its last turning rate the next step's, its last plan the
    #: preview's), so the swing foot's target no longer moves (1: never
    #: committed, the controller re-plans ``f_0`` every cycle to touchdown;
    #: the path itself stops moving horizontally at ``swing_end``). 0.55:
    #: measured with 0.4 to 1 (docs/fullbody.md), the only value tried that
    #: reached all three shipped maps with the planner.
    commit: float = 0.55
    #: Smallest lateral distance (m) between the sole points, along the stance
    #: foot's lateral axis: a controller target closer to (or across) the
    #: stance foot is moved out to it (0: off). The controller has no such
    #: row; the G1's legs cannot put the feet side by side or cross them.
    min_foot_width: float = 0.0
    #: MuJoCo's ``impratio`` with elliptic friction cones (0: MuJoCo's default
    #: pyramidal cones, impratio 1). Above 1 it makes friction harder, so the
    #: stance foot creeps less under the swing leg's reaction (MuJoCo's
    #: documentation recommends it against slip).
    impratio: float = 0.0
    #: With a planner: the controller is given the next subgoal when the CoM
    #: is within this of the current one, m (0.4: the LIP plant's
    #: ``rrt.switch_radius``). Measured with the planner (docs/fullbody.md):
    #: with 0.4 the body reached `circles` and fell on `paper` (81 s, 0.44 m
    #: before the first subgoal, the plan's feet going back and forth as the
    #: controller slowed down for it) and `simple`; with 0.8 it reached
    #: `paper` and fell on `circles` and `simple`.
    switch_radius: float = 0.4
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
    #: planned one when ``min_foot_width`` moved it).
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
        self.floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
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

    def zmp(self) -> Optional[np.ndarray]:
        """The measured ZMP (x, y, m, W): the centre of pressure of the normal
        contact forces between the robot and the floor (None in the air)."""
        total, moment = 0.0, np.zeros(2)
        f = np.zeros(6)
        for i in range(self.d.ncon):
            c = self.d.contact[i]
            if c.geom1 != self.floor and c.geom2 != self.floor:
                continue
            mujoco.mj_contactForce(self.m, self.d, i, f)
            total += f[0]
            moment += f[0] * c.pos[:2]
        return moment / total if total > 1e-6 else None

    def foot_cop(self, side: str):
        """A foot's centre of pressure on the floor (x, y, m, W) and its normal
        force (N); (None, 0) in the air."""
        total, moment = 0.0, np.zeros(2)
        f = np.zeros(6)
        b = self.foot_body[side]
        for i in range(self.d.ncon):
            c = self.d.contact[i]
            if self.floor not in (c.geom1, c.geom2) or b not in (self.m.geom_bodyid[c.geom1], self.m.geom_bodyid[c.geom2]):
                continue
            mujoco.mj_contactForce(self.m, self.d, i, f)
            total += f[0]
            moment += f[0] * c.pos[:2]
        return (moment / total, total) if total > 1e-6 else (None, 0.0)

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


def shift_weight(w: walker.Walker, options: Options) -> None:
    """The start: from standing with the CoM between the soles, the CoM moves
    ``initial_shift`` of the way over the walker's stance sole in
    ``settle_time`` (double support, a quintic in time)."""
    mid = (w.soles["left"] + w.soles["right"]) / 2.0
    goal = mid + options.initial_shift * (w.soles[w.stance] - mid)
    ticks = max(1, round(options.settle_time / w.dt))
    sign = 1.0 if w.stance == "left" else -1.0
    yaw = w.yaws[w.stance]
    for k in range(ticks):
        s = gait.smoothstep((k + 1) / ticks)
        w.stand(mid + s * (goal - mid), yaw, 0.5 + 0.5 * options.initial_shift * s * sign)


def run(
    scenario: Dict[str, Any],
    config: Dict[str, Any],
    options: Options,
    log=None,
    trace=None,
    subgoals: Optional[Sequence[Sequence[float]]] = None,
) -> Dict[str, Any]:
    """Walks ``scenario`` (``ldcbf_nav.load_scenario``'s dict) with the
    controller configured by ``config``; returns the summary, the per-step
    records and the sampled paths (see ``report.py``). ``subgoals`` (W, m;
    the last one the goal): the controller is given them in order, the next
    when the CoM is within ``options.switch_radius`` of the current one, as the LIP
    plant follows its planner's subgoals; ``None``: the goal alone."""
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
    per_control = max(1, round(options.control_period / dt))
    goal = np.asarray(scenario["goal"], dtype=float)
    waypoints = [np.asarray(g, dtype=float) for g in subgoals] if subgoals is not None and len(subgoals) else [goal]
    current = 0
    time_limit = options.time_limit if options.time_limit is not None else scenario["time_limit"]

    # Start: standing in double support, then the CoM over the stance sole.
    start = np.asarray(scenario["start"], dtype=float)
    heading = float(scenario["start_heading"])
    R = wbc.yaw_matrix(heading)
    soles = {side: start + (R @ [0.0, y, 0.0])[:2] for side, y in (("left", robot.STANCE_HALF_WIDTH), ("right", -robot.STANCE_HALF_WIDTH))}
    ik = wbc.WholeBodyIK(dt)
    q = ik.settle(wbc.foot_pose([*soles["left"], 0.0], heading), wbc.foot_pose([*soles["right"], 0.0], heading), [*start, H], heading)
    body.set_pose(ik.robot.get_T_world_fbase(), q)
    w = walker.Walker(body, ik, options, H, config["gravity"], T, scenario["stance"], soles, {"left": heading, "right": heading})
    shift_weight(w, options)

    target = w.soles[w.swing].copy()
    latest = target.copy()
    future: List[np.ndarray] = []
    omega = 0.0
    next_omega = 0.0
    heading_ref = heading
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
    committed = 0
    t0 = time.perf_counter()
    t = 0.0
    tick = 0
    last_status = ""
    max_ticks = round(time_limit / dt)
    while tick < max_ticks:
        if tick % per_control == 0:
            com = body.com()
            vel = body.com_velocity()
            while current + 1 < len(waypoints) and np.linalg.norm(com[:2] - waypoints[current]) <= options.switch_radius:
                current += 1
            if w.tick_in_step < options.commit * w.per_step:
                out = ctl.step(
                    com_position=com[:2],
                    com_velocity=vel[:2],
                    heading=body.heading(),
                    turning_rate=omega,
                    stance_foot=w.soles[w.stance],
                    stance_side=w.stance,
                    time_in_step=w.time_in_step,
                    goal=waypoints[current],
                    obstacles=obstacles,
                )
                last_status = out["status"]
                status_counts[last_status] = status_counts.get(last_status, 0) + 1
                latest = np.asarray(out["foot_target"], dtype=float)
                target, moved = separated(latest, w.soles[w.stance], w.yaws[w.stance], w.swing, options.min_foot_width)
                widened += int(moved)
                future = [np.asarray(f, dtype=float) for f in out["plan"]["feet"][1:]]
                next_omega = float(out["turning_rate"])
            else:
                committed += 1
            if trace:
                trace(
                    f"t={t:6.3f} com {com.round(3)} v {vel[:2].round(2)} ref {w.com_ref.round(3)} "
                    f"stance {w.stance} {w.soles[w.stance].round(3)} target {target.round(3)} swing {body.sole(w.swing).round(3)}"
                )
            samples["t"].append(t)
            samples["com"].append(com.copy())
            samples["left"].append(body.sole("left").copy())
            samples["right"].append(body.sole("right").copy())
            samples["links"].append(d.xpos[tracked_ids].copy())
            if np.linalg.norm(com[:2] - goal) <= scenario["success_radius"]:
                reached = True
                break
            min_clear = min(min_clear, body.clearance())
        # The heading integrates the turning rate in force (as in the LIP plant).
        heading_ref += omega * dt
        land_yaw = heading_ref + omega * (T - w.time_in_step - dt)
        landing = w.tick(target, land_yaw, future, heading_ref)
        tick += 1
        t = tick * dt
        if renderer is not None and tick % per_frame == 0:
            camera.lookat[:] = body.com()
            renderer.update_scene(d, camera)
            frames.append(renderer.render().copy())
        for link in body.obstacle_contacts():
            contacts[link] = contacts.get(link, 0) + 1
            if first_contact is None:
                first_contact = t
        if body.fallen():
            fell = True
            break
        if landing is not None:
            err = float(np.linalg.norm(landing.sole[:2] - latest))
            com = body.com()
            steps.append(
                StepRecord(
                    len(steps) + 1, t, landing.side, target[0], target[1], latest[0], latest[1], landing.path_end[0], landing.path_end[1],
                    landing.sole[0], landing.sole[1], landing.yaw, err, com[0], com[1], last_status,
                )
            )
            if log:
                log(
                    f"t={t:6.2f} step {len(steps):3d} {landing.side:5s} error {err * 100:5.1f} cm "
                    f"target ({latest[0]:.3f}, {latest[1]:.3f}) landed ({landing.sole[0]:.3f}, {landing.sole[1]:.3f}) "
                    f"com ({com[0]:.2f}, {com[1]:.2f})"
                )
            omega = next_omega
            # The next swing foot's target is unknown until the next cycle:
            # it holds where it stands.
            target = w.soles[w.swing].copy()
            latest = target.copy()
            future = []
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
        "subgoals": [[float(x) for x in g] for g in waypoints],
        "subgoals_passed": current,
        "ik_soft_feet_ticks": ik.soft_ticks,
        "widened_targets": widened,
        "committed_cycles": committed,
        "physics_dt": dt,
    }
    return {"frames": frames, "summary": summary, "steps": steps, "samples": samples, "tracked": tracked, "obstacles": obstacles, "goal": goal, "start": start}
