"""Walking a sequence of footsteps with the body, one physics tick at a time:
the ZMP reference of the footsteps (a double support at the start of each
step), the CoM from it by preview control (``preview.py``), the swing foot's
path, the IK and the servos (``drive``).

Timing of a step of ``T`` s: for the first ``double_support`` s both feet
are on the ground and the ZMP reference moves in a straight line from the
previous stance sole to the new one; then the swing foot (the previous
stance foot) lifts, and it lands on its target at ``T``, when the support
changes sides (as in the controller's model, whose ZMP is at the stance
sole for the whole step).

Frames and units: world W (z up, ground z = 0), m, rad, s. Sole points are
(x, y) on the ground.
"""

import dataclasses
import math
from typing import Dict, List, Optional, Sequence

import mujoco
import numpy as np

from . import gait, preview, wbc


@dataclasses.dataclass
class Gait:
    """The walking pattern's settings (``--set`` keys of ``sim.Options``)."""

    #: Swing foot apex above the ground, m.
    swing_height: float = 0.04
    #: Double support at the start of each step, s.
    double_support: float = 0.08
    #: Preview controller's period (s) and look-ahead (s).
    preview_period: float = 0.01
    preview_horizon: float = 1.2
    #: CoM feedback gain of the IK's CoM target: ``ref + gain (ref - measured)``
    #: in the horizontal plane (0: open loop).
    com_feedback: float = 0.5
    #: Add the static gravity torques of the IK configuration (placo, on the
    #: supporting feet) to the servos as a feed-forward.
    gravity_feedforward: bool = True
    #: Swing-foot feedback gain: the IK's swing target is ``path + gain (path -
    #: measured)`` in the horizontal plane (0: open loop).
    swing_feedback: float = 0.0
    #: The stabiliser (``Stabiliser``): the CoM command's acceleration per m
    #: of measured ZMP ahead of the desired one (1/s^2; 0: off) ...
    zmp_admittance: float = 0.0
    #: ... the desired ZMP's gain on the DCM error, ``p_d = p_ref + dcm_gain
    #: (xi - xi_ref)`` (dimensionless; 0: the reference ZMP) ...
    dcm_gain: float = 0.0
    #: ... the time constant (s) pulling the CoM offset back to zero, and its
    #: largest size (m).
    stabiliser_leak: float = 0.5
    stabiliser_limit: float = 0.05
    #: Foot damping control (``FootDamping``): ankle rotation rate (rad/s) per
    #: m of a supporting foot's centre of pressure away from its sole point
    #: (0: off), and the time constant (s) back to the IK's ankle angles.
    foot_damping: float = 5.0
    foot_damping_leak: float = 0.2
    #: The swing foot moves horizontally until this fraction of its swing
    #: (lift-off 0, touchdown 1), then comes down vertically.
    swing_end: float = 0.95


def drive(body, ik: wbc.WholeBodyIK, gait_: Gait, left: np.ndarray, right: np.ndarray, com: np.ndarray, yaw: float, left_share: float, offsets: Optional[Dict[str, float]] = None) -> None:
    """One physics tick: the IK on the references (foot poses 4x4, CoM
    reference (x, y, z), trunk yaw), the CoM feedback, the servos' targets
    and feed-forward (the weight carried by the left foot for ``left_share``
    in [0, 1]) with ``offsets`` (rad) added to the joint targets, then the
    MuJoCo step."""
    target = np.array(com, dtype=float)
    if gait_.com_feedback:
        target[:2] += gait_.com_feedback * (target[:2] - body.com()[:2])
    ik.place(left, right, target, yaw)
    q = ik.solve(1)
    if offsets:
        q = {n: v + offsets.get(n, 0.0) for n, v in q.items()}
    body.command(q, ik.gravity_torques(left_share) if gait_.gravity_feedforward else None)
    mujoco.mj_step(body.m, body.d)


def extend(chain: List[np.ndarray], count: int) -> List[np.ndarray]:
    """The sole points ``chain`` (stance first, then the planned steps)
    continued to ``count`` points: each new one is the one two before it
    moved as the other foot last moved (``c[k] = c[k-2] + c[k-1] - c[k-3]``);
    with fewer than 4 points the last is repeated (the plan stops)."""
    out = [np.asarray(c, dtype=float) for c in chain]
    while len(out) < count:
        out.append(out[-2] + out[-1] - out[-3] if len(out) >= 4 else out[-1])
    return out


def zmp_reference(times: np.ndarray, tau: float, T: float, t_ds: float, zmp_from: np.ndarray, chain: Sequence[np.ndarray]) -> np.ndarray:
    """The ZMP reference (len(times), 2) at ``times`` (s from now), ``tau`` s
    into the current step of ``T`` s: step ``i`` (0 the current one) has its
    ZMP at ``chain[i]`` (``extend``ed as needed) after a straight move of
    ``t_ds`` s from the previous one (``zmp_from`` for the current step)."""
    t = np.asarray(times) + tau
    i = np.floor(t / T).astype(int)
    pts = np.array(extend(list(chain), int(i.max()) + 1))
    prev = np.vstack([zmp_from, pts[:-1]])
    s = np.clip((t - i * T) / t_ds, 0.0, 1.0) if t_ds > 0 else np.ones_like(t)
    return prev[i] + s[:, None] * (pts[i] - prev[i])


class Stabiliser:
    """A CoM admittance on the measured ZMP: the IK's CoM command is the
    reference plus an offset ``delta`` (m, W, horizontal) whose acceleration
    is ``A (p - p_d) - 2 delta' / tau - delta / tau^2``: a measured ZMP ``p``
    ahead of the desired ``p_d`` moves the CoM forward, which moves the ZMP
    back (``p = c - c'' H / g``). The desired ZMP is the reference plus
    ``dcm_gain`` times the error of the divergent component of motion
    ``xi = c + c' / omega`` (measured minus reference), so that a CoM running
    ahead is caught. The measured ZMP is low-pass filtered (``filter`` s)."""

    def __init__(self, gait_: Gait, omega: float, dt: float, filter: float = 0.01) -> None:
        self.gait, self.omega, self.dt = gait_, omega, dt
        self.alpha = dt / (dt + filter)
        self.delta = np.zeros(2)
        self.rate = np.zeros(2)
        self.zmp: Optional[np.ndarray] = None

    def offset(self, zmp_ref: np.ndarray, com_ref: np.ndarray, vel_ref: np.ndarray, com: np.ndarray, vel: np.ndarray, zmp: Optional[np.ndarray]) -> np.ndarray:
        """One tick: the references and the measurements (m, m/s, W); returns
        the CoM offset (m)."""
        g = self.gait
        if not g.zmp_admittance:
            return self.delta
        if zmp is not None:
            self.zmp = zmp if self.zmp is None else self.zmp + self.alpha * (zmp - self.zmp)
        if self.zmp is None:
            return self.delta
        xi_err = (com + vel / self.omega) - (com_ref + vel_ref / self.omega)
        desired = zmp_ref + g.dcm_gain * xi_err
        tau = g.stabiliser_leak
        acc = g.zmp_admittance * (self.zmp - desired) - 2.0 * self.rate / tau - self.delta / tau**2
        self.rate = self.rate + acc * self.dt
        self.delta = self.delta + self.rate * self.dt
        n = np.linalg.norm(self.delta)
        if n > g.stabiliser_limit:
            self.delta *= g.stabiliser_limit / n
            self.rate[:] = 0.0
        return self.delta


class FootDamping:
    """Keeps the supporting feet flat: each foot's ankle pitch and roll
    targets are offset from the IK's, at a rate ``foot_damping`` times the
    foot's centre of pressure away from its sole point (in the foot frame),
    leaking back with ``foot_damping_leak``: a centre of pressure at the toe
    turns the toe up, off the edge the stiff ankle servo would roll it
    onto (the ankle torque is then what the foot can carry)."""

    def __init__(self, gait_: Gait, dt: float) -> None:
        self.gait, self.dt = gait_, dt
        self.angles = {s: np.zeros(2) for s in ("left", "right")}

    def offsets(self, body, supporting: Sequence[str]) -> Dict[str, float]:
        """One tick: the ankle target offsets (rad) by joint name."""
        g = self.gait
        out: Dict[str, float] = {}
        if not g.foot_damping:
            return out
        for side, a in self.angles.items():
            cop, force = body.foot_cop(side) if side in supporting else (None, 0.0)
            rate = -a / g.foot_damping_leak
            if cop is not None and force > 20.0:
                R = body.d.xmat[body.foot_body[side]].reshape(3, 3)
                e = R[:2, :2].T @ (cop - body.sole(side)[:2])
                rate = rate + g.foot_damping * np.array([-e[0], e[1]])
            self.angles[side] = a + rate * self.dt
            out[f"{side}_ankle_pitch_joint"], out[f"{side}_ankle_roll_joint"] = self.angles[side]
        return out


@dataclasses.dataclass
class Landing:
    """A step's end: the landed foot (W)."""

    side: str
    target: np.ndarray
    sole: np.ndarray
    yaw: float
    #: The swing path's last horizontal target.
    path_end: np.ndarray


class Walker:
    """The stepping state of the body: which foot stands where, the swing
    foot's path, the CoM reference; ``tick`` advances it one physics tick."""

    def __init__(self, body, ik: wbc.WholeBodyIK, gait_: Gait, H: float, g: float, T: float, stance: str, soles: Dict[str, np.ndarray], yaws: Dict[str, float]) -> None:
        self.body, self.ik, self.gait = body, ik, gait_
        self.H, self.T = H, T
        self.dt = body.m.opt.timestep
        self.per_step = round(T / self.dt)
        self.ds_ticks = round(gait_.double_support / self.dt)
        self.lift = self.ds_ticks / self.per_step
        self.per_preview = max(1, round(gait_.preview_period / self.dt))
        self.preview = preview.Preview(H, g, self.per_preview * self.dt, gait_.preview_horizon)
        self.horizon_times = (np.arange(self.preview.n) + 1) * self.preview.dt
        self.stance = stance
        self.swing = "right" if stance == "left" else "left"
        self.soles = {k: np.asarray(v, dtype=float)[:2].copy() for k, v in soles.items()}
        self.yaws = dict(yaws)
        self.zmp_from = self.soles[stance].copy()
        self.tick_in_step = 0
        self.ticks = 0
        self.path = self._new_path()
        self.com_ref = body.com()[:2].copy()
        self.preview.reset(self.com_ref)
        self.stabiliser = Stabiliser(gait_, math.sqrt(g / H), self.dt)
        self.damping = FootDamping(gait_, self.dt)

    def _new_path(self) -> gait.Swing:
        lift = self.lift
        return gait.Swing(self.body.sole(self.swing)[:2], lift, lift + self.gait.swing_end * (1.0 - lift))

    def stand(self, com_xy: np.ndarray, yaw: float, left_share: float) -> None:
        """A tick in double support at the landed feet, the CoM at ``com_xy``
        (the start, before walking)."""
        feet = {s: wbc.foot_pose([*self.soles[s], 0.0], self.yaws[s]) for s in ("left", "right")}
        drive(self.body, self.ik, self.gait, feet["left"], feet["right"], np.array([*com_xy, self.H]), yaw, left_share)
        self.com_ref = np.asarray(com_xy, dtype=float).copy()
        self.preview.reset(self.com_ref)

    def tick(self, target: np.ndarray, land_yaw: float, future: Sequence[np.ndarray], trunk_yaw: float) -> Optional[Landing]:
        """One physics tick towards the swing foot's ``target`` (x, y) and
        landing yaw; ``future`` the planned sole points after it (for the
        preview); the trunk yawed to ``trunk_yaw``. Returns the landing at a
        step's end, else None."""
        tau = self.tick_in_step * self.dt
        if self.ticks % self.per_preview == 0:
            chain = [self.soles[self.stance], np.asarray(target, dtype=float), *future]
            self.preview.advance(zmp_reference(self.horizon_times, tau, self.T, self.gait.double_support, self.zmp_from, chain))
        s = (self.ticks % self.per_preview + 1) * self.dt
        self.com_ref, vel_ref = self.preview.sample(s)
        body = self.body
        delta = self.stabiliser.delta
        if self.gait.zmp_admittance:
            # The stabiliser's references and measurements, only when it is on.
            chain = [self.soles[self.stance], np.asarray(target, dtype=float)]
            zmp_ref = zmp_reference(np.zeros(1), tau, self.T, self.gait.double_support, self.zmp_from, chain)[0]
            delta = self.stabiliser.offset(zmp_ref, self.com_ref, vel_ref, body.com()[:2], body.com_velocity()[:2], body.zmp())
        phase = self.tick_in_step / self.per_step
        swing_xy = self.path.advance(target, phase, self.dt, self.T)
        cmd_xy = swing_xy + self.gait.swing_feedback * (swing_xy - self.body.sole(self.swing)[:2]) if phase >= self.lift else swing_xy
        z = gait.swing_height((self.tick_in_step + 1) / self.per_step, self.gait.swing_height, self.lift)
        start_yaw = self.yaws[self.swing]
        yaw = start_yaw + (land_yaw - start_yaw) * gait.smoothstep((phase - self.lift) / (1.0 - self.lift))
        stance_pose = wbc.foot_pose([*self.soles[self.stance], 0.0], self.yaws[self.stance])
        swing_pose = wbc.foot_pose([cmd_xy[0], cmd_xy[1], z], yaw)
        left, right = (stance_pose, swing_pose) if self.stance == "left" else (swing_pose, stance_pose)
        # The weight moves to the stance foot during the double support.
        w = min(1.0, (self.tick_in_step + 1) / self.ds_ticks) if self.ds_ticks else 1.0
        share = w if self.stance == "left" else 1.0 - w
        supporting = ("left", "right") if self.tick_in_step < self.ds_ticks else (self.stance,)
        offsets = self.damping.offsets(body, supporting)
        drive(body, self.ik, self.gait, left, right, np.array([*(self.com_ref + delta), self.H]), trunk_yaw, share, offsets)
        self.ticks += 1
        self.tick_in_step += 1
        if self.tick_in_step < self.per_step:
            return None
        landed = self.body.sole(self.swing)
        out = Landing(self.swing, np.asarray(target, dtype=float).copy(), landed.copy(), land_yaw, self.path.x.copy())
        self.zmp_from = self.soles[self.stance].copy()
        self.soles[self.swing] = landed[:2].copy()
        self.yaws[self.swing] = land_yaw
        self.stance, self.swing = self.swing, self.stance
        self.tick_in_step = 0
        self.path = self._new_path()
        return out

    @property
    def time_in_step(self) -> float:
        """Seconds since the current step began."""
        return self.tick_in_step * self.dt
