"""The vendored Unitree G1 (``model/``, see ``model/README.md``) and the
MuJoCo world around it: the ground and the scenario's obstacles as prisms."""

import pathlib
from typing import List, Sequence

import mujoco
import numpy as np

DIR = pathlib.Path(__file__).resolve().parent / "model"
#: placo's URDF (kinematics and inertias of the wheel's G1, no meshes).
URDF = DIR / "g1.urdf"
#: MuJoCo's model of the same robot (collision boxes, position servos).
MJCF = DIR / "g1.xml"

#: Contact time constant (s) and damping ratio of every geom (MuJoCo's
#: ``solref``): stiffer than MuJoCo's default 0.02 s, under which the foot's
#: point contacts sink unevenly under an off-centre load and the stance foot
#: rolls with the CoM (measured: 0.025 rad of foot roll standing in double
#: support, a fall when lifting a foot). At least twice the time step.
SOLREF = (0.005, 1.0)

#: Geom group of the obstacles (robot geoms are in group 0).
OBSTACLE_GROUP = 3


def world(obstacles: Sequence[np.ndarray], height: float) -> mujoco.MjModel:
    """The G1 on a flat floor with each obstacle (convex (k, 2) vertex array, m,
    W) extruded from z = 0 to ``height`` (m) as a mesh prism named
    ``obstacle<i>``. Robot geoms collide with the floor and the obstacles,
    not with each other."""
    spec = mujoco.MjSpec.from_file(str(MJCF))
    floor = spec.worldbody.add_geom()
    floor.name = "floor"
    floor.type = mujoco.mjtGeom.mjGEOM_PLANE
    floor.size = [0.0, 0.0, 0.05]
    floor.contype = 0
    floor.conaffinity = 1
    floor.friction = [1.0, 0.005, 0.0001]
    for i, poly in enumerate(obstacles):
        poly = np.asarray(poly, dtype=float)
        verts: List[float] = []
        for z in (0.0, height):
            for x, y in poly:
                verts += [x, y, z]
        mesh = spec.add_mesh()
        mesh.name = f"prism{i}"
        mesh.uservert = verts
        geom = spec.worldbody.add_geom()
        geom.name = f"obstacle{i}"
        geom.type = mujoco.mjtGeom.mjGEOM_MESH
        geom.meshname = mesh.name
        geom.contype = 0
        geom.conaffinity = 1
        geom.group = OBSTACLE_GROUP
        geom.rgba = [0.8, 0.3, 0.3, 0.5]
    for geom in spec.geoms:
        geom.solref = SOLREF
    light = spec.worldbody.add_light()
    light.pos = [0.0, 0.0, 5.0]
    light.dir = [0.0, 0.0, -1.0]
    return spec.compile()
