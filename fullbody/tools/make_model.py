"""Builds the vendored Unitree G1 model (``ldcbf_fullbody/model/``) from the
``example-robot-data`` wheel (BSD-3-Clause), once, by hand:

    python3 -m pip install example-robot-data mujoco
    python3 fullbody/tools/make_model.py

It writes

* ``g1.urdf``: the wheel's ``g1_29dof_rev_1_0.urdf`` without its ``<visual>``
  and mesh ``<collision>`` elements (kinematics and inertias unchanged), read
  by placo for the whole-body inverse kinematics;
* ``g1.xml``: the MuJoCo model of the same URDF, every collision mesh replaced
  by the box MuJoCo fits to it (``fitaabb``: the mesh's bounding box in its
  inertial frame, so a box contains its mesh), the four foot spheres and the
  primitive shoulder cylinders kept, a free joint on the pelvis, one position
  actuator per joint (gains below, torque limits from the URDF's ``effort``);
* ``LICENSE``: the wheel's licence.

Nothing is downloaded at run time: the package reads only these files.
"""

import pathlib
import re
import shutil
import sys
import xml.etree.ElementTree as ET

import mujoco

OUT = pathlib.Path(__file__).resolve().parents[1] / "ldcbf_fullbody" / "model"
URDF_NAME = "g1_29dof_rev_1_0.urdf"

# Position-servo stiffness (N m/rad) by joint-name fragment, and the joint
# damping (N m s/rad) and armature (kg m^2) added to every joint. The legs'
# stiffness must exceed the body's gravity stiffness m g H (about 220 N m/rad)
# with hip, knee and ankle compliances in series: at a third of these values
# the standing CoM drifts outward and the body falls (docs/fullbody.md).
KP = {"hip": 3000.0, "knee": 3000.0, "ankle": 3000.0, "waist": 3000.0, "shoulder": 300.0, "elbow": 300.0, "wrist": 50.0}
DAMPING = {"hip": 30.0, "knee": 30.0, "ankle": 30.0, "waist": 30.0, "shoulder": 3.0, "elbow": 3.0, "wrist": 1.0}
ARMATURE = 0.03


def robot_dir() -> pathlib.Path:
    """The wheel's ``g1_description`` folder."""
    import site

    for base in site.getsitepackages() + [site.getusersitepackages()]:
        d = pathlib.Path(base) / "cmeel.prefix/share/example-robot-data/robots/g1_description"
        if d.is_dir():
            return d
    sys.exit("error: example-robot-data is not installed (python3 -m pip install example-robot-data)")


def gain(table: dict, joint: str) -> float:
    for key, value in table.items():
        if key in joint:
            return value
    raise KeyError(joint)


def stripped_urdf(text: str) -> str:
    root = ET.fromstring(text)
    for link in root.findall("link"):
        for vis in link.findall("visual"):
            link.remove(vis)
        for col in link.findall("collision"):
            if col.find("geometry/mesh") is not None:
                link.remove(col)
    return ET.tostring(root, encoding="unicode")


def mjcf(src: pathlib.Path, text: str) -> str:
    text = re.sub(r'filename="[^"]*/meshes/', 'filename="', text)
    compiler = (
        f'<mujoco><compiler meshdir="{src}/meshes" discardvisual="true" '
        'fusestatic="false" strippath="true" fitaabb="true"/></mujoco>'
    )
    text = re.sub(r"(<robot[^>]*>)", r"\1" + compiler, text, count=1)
    spec = mujoco.MjSpec.from_string(text)
    for g in spec.geoms:
        if g.type == mujoco.mjtGeom.mjGEOM_MESH:
            g.type = mujoco.mjtGeom.mjGEOM_BOX
    fitted = spec.compile()
    for i, g in enumerate(spec.geoms):
        if g.meshname:
            g.size = fitted.geom_size[i]
            g.pos = fitted.geom_pos[i]
            g.quat = fitted.geom_quat[i]
            g.meshname = ""
        # Robot geoms touch the world (floor, obstacles) but not each other.
        g.contype = 1
        g.conaffinity = 0
        g.condim = 3
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    spec.compiler.meshdir = ""
    spec.modelname = "g1"
    spec.option.timestep = 0.002
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    pelvis = spec.body("pelvis")
    pelvis.pos = [0.0, 0.0, 0.8]
    pelvis.add_freejoint(name="floating_base")
    for joint in spec.joints:
        if joint.type != mujoco.mjtJoint.mjJNT_HINGE:
            continue
        joint.damping = [gain(DAMPING, joint.name), 0.0, 0.0]
        joint.armature = ARMATURE
        act = spec.add_actuator(name=joint.name, target=joint.name)
        act.trntype = mujoco.mjtTrn.mjTRN_JOINT
        kp = gain(KP, joint.name)
        act.set_to_position(kp=kp)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = joint.actfrcrange
        act.ctrlrange = joint.range
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    spec.compile()
    return spec.to_xml()


def main() -> None:
    src = robot_dir()
    text = (src / "urdf" / URDF_NAME).read_text()
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "g1.urdf").write_text(stripped_urdf(text))
    (OUT / "g1.xml").write_text(mjcf(src, text))
    import importlib.metadata

    dist = importlib.metadata.distribution("example-robot-data")
    lic = [f for f in dist.files or [] if str(f).endswith("dist-info/licenses/LICENSE")]
    if not lic:
        sys.exit("error: example-robot-data ships no LICENSE")
    shutil.copy(dist.locate_file(lic[0]), OUT / "LICENSE")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
