"""The node's ROS 2 messages as Cyclone DDS IDL types, with ROS 2's DDS type
names (`pkg::msg::dds_::Type_`): an independent definition of the wire format
of `ros2/src/msgs.rs` (ROS 2 Jazzy layouts)."""

# (No `from __future__ import annotations`: cyclonedds reads the real types.)

from dataclasses import dataclass, field, fields, is_dataclass
import typing

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, byte, float32, float64, int32, sequence, uint8, uint32


def _t(pkg: str, name: str) -> str:
    return f"{pkg}::msg::dds_::{name}_"


@dataclass
class Time(IdlStruct, typename=_t("builtin_interfaces", "Time")):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Duration(IdlStruct, typename=_t("builtin_interfaces", "Duration")):
    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Header(IdlStruct, typename=_t("std_msgs", "Header")):
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class Point(IdlStruct, typename=_t("geometry_msgs", "Point")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Vector3(IdlStruct, typename=_t("geometry_msgs", "Vector3")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename=_t("geometry_msgs", "Quaternion")):
    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Pose(IdlStruct, typename=_t("geometry_msgs", "Pose")):
    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseStamped(IdlStruct, typename=_t("geometry_msgs", "PoseStamped")):
    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@dataclass
class Twist(IdlStruct, typename=_t("geometry_msgs", "Twist")):
    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


@dataclass
class PoseWithCovariance(IdlStruct, typename=_t("geometry_msgs", "PoseWithCovariance")):
    pose: Pose = field(default_factory=Pose)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class TwistWithCovariance(IdlStruct, typename=_t("geometry_msgs", "TwistWithCovariance")):
    twist: Twist = field(default_factory=Twist)
    covariance: array[float64, 36] = field(default_factory=lambda: [0.0] * 36)


@dataclass
class Odometry(IdlStruct, typename=_t("nav_msgs", "Odometry")):
    header: Header = field(default_factory=Header)
    child_frame_id: str = ""
    pose: PoseWithCovariance = field(default_factory=PoseWithCovariance)
    twist: TwistWithCovariance = field(default_factory=TwistWithCovariance)


@dataclass
class Path(IdlStruct, typename=_t("nav_msgs", "Path")):
    header: Header = field(default_factory=Header)
    poses: sequence[PoseStamped] = field(default_factory=list)


@dataclass
class ColorRGBA(IdlStruct, typename=_t("std_msgs", "ColorRGBA")):
    r: float32 = 0.0
    g: float32 = 0.0
    b: float32 = 0.0
    a: float32 = 0.0


@dataclass
class CompressedImage(IdlStruct, typename=_t("sensor_msgs", "CompressedImage")):
    header: Header = field(default_factory=Header)
    format: str = ""
    data: sequence[uint8] = field(default_factory=list)


@dataclass
class UVCoordinate(IdlStruct, typename=_t("visualization_msgs", "UVCoordinate")):
    u: float32 = 0.0
    v: float32 = 0.0


@dataclass
class MeshFile(IdlStruct, typename=_t("visualization_msgs", "MeshFile")):
    filename: str = ""
    data: sequence[uint8] = field(default_factory=list)


@dataclass
class Marker(IdlStruct, typename=_t("visualization_msgs", "Marker")):
    header: Header = field(default_factory=Header)
    ns: str = ""
    id: int32 = 0
    type: int32 = 0
    action: int32 = 0
    pose: Pose = field(default_factory=Pose)
    scale: Vector3 = field(default_factory=Vector3)
    color: ColorRGBA = field(default_factory=ColorRGBA)
    lifetime: Duration = field(default_factory=Duration)
    frame_locked: bool = False
    points: sequence[Point] = field(default_factory=list)
    colors: sequence[ColorRGBA] = field(default_factory=list)
    texture_resource: str = ""
    texture: CompressedImage = field(default_factory=CompressedImage)
    uv_coordinates: sequence[UVCoordinate] = field(default_factory=list)
    text: str = ""
    mesh_resource: str = ""
    mesh_file: MeshFile = field(default_factory=MeshFile)
    mesh_use_embedded_materials: bool = False


@dataclass
class MarkerArray(IdlStruct, typename=_t("visualization_msgs", "MarkerArray")):
    markers: sequence[Marker] = field(default_factory=list)


@dataclass
class KeyValue(IdlStruct, typename=_t("diagnostic_msgs", "KeyValue")):
    key: str = ""
    value: str = ""


@dataclass
class DiagnosticStatus(IdlStruct, typename=_t("diagnostic_msgs", "DiagnosticStatus")):
    level: byte = 0
    name: str = ""
    message: str = ""
    hardware_id: str = ""
    values: sequence[KeyValue] = field(default_factory=list)


@dataclass
class DiagnosticArray(IdlStruct, typename=_t("diagnostic_msgs", "DiagnosticArray")):
    header: Header = field(default_factory=Header)
    status: sequence[DiagnosticStatus] = field(default_factory=list)


@dataclass
class LaserScan(IdlStruct, typename=_t("sensor_msgs", "LaserScan")):
    header: Header = field(default_factory=Header)
    angle_min: float32 = 0.0
    angle_max: float32 = 0.0
    angle_increment: float32 = 0.0
    time_increment: float32 = 0.0
    scan_time: float32 = 0.0
    range_min: float32 = 0.0
    range_max: float32 = 0.0
    ranges: sequence[float32] = field(default_factory=list)
    intensities: sequence[float32] = field(default_factory=list)


@dataclass
class GaitState(IdlStruct, typename=_t("ldcbf_msgs", "GaitState")):
    header: Header = field(default_factory=Header)
    stance_side: uint8 = 0
    stance_foot: Point = field(default_factory=Point)
    time_in_step: float64 = 0.0
    turning_rate: float64 = 0.0


@dataclass
class FootstepCommand(IdlStruct, typename=_t("ldcbf_msgs", "FootstepCommand")):
    header: Header = field(default_factory=Header)
    result: uint8 = 0
    source: uint8 = 0
    status: str = ""
    foot_target: Point = field(default_factory=Point)
    turning_rate: float64 = 0.0
    planned_feet: sequence[Point] = field(default_factory=list)
    first_side: uint8 = 0
    predicted_com: sequence[Point] = field(default_factory=list)
    iterations: uint32 = 0
    active_obstacles: uint8 = 0
    relax_gait: float64 = 0.0
    relax_safety: float64 = 0.0


def build(cls, value):
    """An IDL object of type `cls` from the JSON form of `ldcbf-ros2 record`."""
    hints = typing.get_type_hints(cls, include_extras=True)
    kwargs = {}
    for f in fields(cls):
        v = value[f.name]
        hint = hints[f.name]
        base = typing.get_origin(hint) or hint
        if is_dataclass(base):
            kwargs[f.name] = build(base, v)
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            item = _item_type(hint)
            kwargs[f.name] = [build(item, x) for x in v]
        else:
            kwargs[f.name] = v
    return cls(**kwargs)


def _item_type(hint):
    """The element type of a `sequence[T]` annotation."""
    for a in typing.get_args(hint):
        inner = getattr(a, "subtype", None)
        if inner is not None:
            return inner
    raise TypeError(f"not a sequence of structs: {hint}")


def as_dict(obj):
    """The JSON-like form of an IDL object (the inverse of `build`)."""
    if is_dataclass(obj):
        return {f.name: as_dict(getattr(obj, f.name)) for f in fields(obj)}
    if isinstance(obj, list):
        return [as_dict(x) for x in obj]
    return obj
