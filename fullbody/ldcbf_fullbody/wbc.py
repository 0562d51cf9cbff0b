"""Whole-body kinematics: placo's inverse-kinematics solver turns the walking
references (both feet's poses, the CoM position, the trunk's yaw) into joint
position targets, which MuJoCo's position servos track (``sim.py``).

Frames: world W (z up, the ground at z = 0), SI units (m, rad). A foot's
*sole point* is the centre of its four contact spheres projected on the
ground: ``SOLE_OFFSET`` from the ankle-roll frame, in the foot frame. The
controller's footsteps are sole points.

The IK robot is a kinematic copy of the body whose floating base is solved
for (not measured): the feet and the CoM are placed in W where the gait asks,
and the joint angles are what the physical body is given.
"""

from typing import Dict, Sequence

import numpy as np
import placo

from . import model

#: Sole point in the ankle-roll frame (m): the middle of the foot's contact
#: spheres (x in -0.05..0.12, y in -0.03..0.03 in the URDF), on the sole (the
#: spheres' centres are 0.03 m below the frame, radius 0.005 m).
SOLE_OFFSET = np.array([0.035, 0.0, -0.035])

#: Foot frames of the URDF, by side.
FOOT_FRAME = {"left": "left_ankle_roll_link", "right": "right_ankle_roll_link"}
TRUNK_FRAME = "torso_link"
PELVIS_FRAME = "pelvis"

#: The standing posture the IK starts from and the arms and waist are pulled
#: towards (rad): knees bent, arms slightly away from the body.
POSTURE = {
    "left_hip_pitch_joint": -0.5,
    "right_hip_pitch_joint": -0.5,
    "left_knee_joint": 1.0,
    "right_knee_joint": 1.0,
    "left_ankle_pitch_joint": -0.5,
    "right_ankle_pitch_joint": -0.5,
    "left_shoulder_roll_joint": 0.15,
    "right_shoulder_roll_joint": -0.15,
    "left_elbow_joint": 0.9,
    "right_elbow_joint": 0.9,
}

#: Joints held at the posture (with a low weight) rather than left free.
UPPER_BODY = ("waist", "shoulder", "elbow", "wrist")

#: The feet tasks: "hard" (equality constraints of the IK QP) or "soft".
FOOT_PRIORITY = "hard"


def yaw_matrix(yaw: float) -> np.ndarray:
    """Rotation about z by ``yaw`` (rad)."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def foot_pose(sole: Sequence[float], yaw: float) -> np.ndarray:
    """The ankle-roll frame's pose (4x4, W) for a flat foot whose sole point is
    ``sole`` (x, y, z; z = 0 on the ground) with heading ``yaw``."""
    R = yaw_matrix(yaw)
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.asarray(sole, dtype=float) - R @ SOLE_OFFSET
    return T


class WholeBodyIK:
    """placo's kinematics solver on the vendored G1 URDF, with the walking tasks:
    both feet (weight 1000), the CoM (weight 1), the trunk's orientation
    (upright, yawed to the heading), the upper body at its posture."""

    def __init__(self, dt: float) -> None:
        self.robot = placo.RobotWrapper(str(model.URDF), placo.Flags.ignore_collisions)
        self.names = list(self.robot.joint_names())
        for name, value in POSTURE.items():
            self.robot.set_joint(name, value)
        self.robot.update_kinematics()
        self.solver = placo.KinematicsSolver(self.robot)
        self.solver.dt = dt
        self.solver.enable_velocity_limits(False)
        self.feet = {}
        for side, frame in FOOT_FRAME.items():
            task = self.solver.add_frame_task(frame, self.robot.get_T_world_frame(frame))
            task.configure(f"{side}_foot", FOOT_PRIORITY, 1e3, 1e3)
            self.feet[side] = task
        self.com = self.solver.add_com_task(self.robot.com_world())
        self.com.configure("com", "soft", 1.0)
        self.trunk = self.solver.add_orientation_task(TRUNK_FRAME, np.eye(3))
        self.trunk.configure("trunk", "soft", 1.0)
        self.pelvis = self.solver.add_orientation_task(PELVIS_FRAME, np.eye(3))
        self.pelvis.configure("pelvis", "soft", 0.3)
        self.posture = self.solver.add_joints_task()
        self.posture.set_joints({n: POSTURE.get(n, 0.0) for n in self.names if n.startswith(UPPER_BODY)})
        self.posture.configure("posture", "soft", 1e-2)
        self.solver.add_regularization_task(1e-5)
        #: Ticks whose IK had the feet as soft tasks (hard ones infeasible).
        self.soft_ticks = 0

    def place(self, left: np.ndarray, right: np.ndarray, com: Sequence[float], yaw: float) -> None:
        """Sets the references: foot poses (4x4, W), the CoM (m, W), the trunk's yaw (rad)."""
        self.feet["left"].T_world_frame = left
        self.feet["right"].T_world_frame = right
        self.com.target_world = np.asarray(com, dtype=float)
        self.trunk.R_world_frame = yaw_matrix(yaw)
        self.pelvis.R_world_frame = yaw_matrix(yaw)

    def solve(self, iterations: int = 1) -> Dict[str, float]:
        """Runs the solver ``iterations`` times (each a step of ``dt``) and
        returns the joint angles (rad) by joint name."""
        for _ in range(iterations):
            try:
                self.solver.solve(True)
            except RuntimeError:
                # The feet cannot be met exactly within the joint limits: this
                # tick they are soft tasks (weight 1000) instead.
                self.soft_ticks += 1
                for side, task in self.feet.items():
                    task.configure(f"{side}_foot", "soft", 1e3, 1e3)
                self.solver.solve(True)
                for side, task in self.feet.items():
                    task.configure(f"{side}_foot", FOOT_PRIORITY, 1e3, 1e3)
            self.robot.update_kinematics()
        return {n: float(self.robot.get_joint(n)) for n in self.names}

    def gravity_torques(self, left_share: float) -> Dict[str, float]:
        """Joint torques (N m) holding the IK configuration still against
        gravity, the weight carried by the left foot for ``left_share`` in
        [0, 1] and by the right for the rest (placo's static gravity
        compensation with each foot as the support, blended)."""
        tl = self.robot.static_gravity_compensation_torques_dict(FOOT_FRAME["left"])
        tr = self.robot.static_gravity_compensation_torques_dict(FOOT_FRAME["right"])
        return {n: left_share * tl[n] + (1.0 - left_share) * tr[n] for n in self.names}

    def settle(self, left: np.ndarray, right: np.ndarray, com: Sequence[float], yaw: float) -> Dict[str, float]:
        """Places the IK robot on the references, from its posture, until it
        converges (used before the physics starts)."""
        self.place(left, right, com, yaw)
        T = np.eye(4)
        T[:3, :3] = yaw_matrix(yaw)
        T[:3, 3] = [com[0], com[1], com[2] + 0.1]
        self.robot.set_T_world_fbase(T)
        self.robot.update_kinematics()
        return self.solve(200)
