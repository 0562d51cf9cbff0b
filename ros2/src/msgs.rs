//! The ROS 2 messages the node speaks, as Rust types that match the `.msg`
//! definitions field for field and in order (ROS 2 Jazzy), so that serde's
//! CDR encoding (RustDDS) is the wire format of `rmw_cyclonedds` and
//! `rmw_fastrtps`. Fixed-size arrays (`float64[36]`) are Rust arrays; unbounded
//! arrays are `Vec`. Our own messages ([`GaitState`], [`FootstepCommand`]) are
//! `ros2/ldcbf_msgs/msg/*.msg`.

use serde::{Deserialize, Serialize};

/// `builtin_interfaces/msg/Time`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, `< 1e9`.
    pub nanosec: u32,
}

impl Time {
    /// The time `t` s (>= 0; rounded to the ns).
    pub fn from_secs(t: f64) -> Time {
        let ns = (t.max(0.0) * 1e9).round() as u64;
        Time {
            sec: (ns / 1_000_000_000) as i32,
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// `builtin_interfaces/msg/Duration`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Duration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, `< 1e9`.
    pub nanosec: u32,
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Time of the data.
    pub stamp: Time,
    /// Frame of the data.
    pub frame_id: String,
}

/// `geometry_msgs/msg/Point`, m.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// x, m.
    pub x: f64,
    /// y, m.
    pub y: f64,
    /// z, m.
    pub z: f64,
}

/// `geometry_msgs/msg/Vector3`.
pub type Vector3 = Point;

/// `geometry_msgs/msg/Quaternion`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position, m.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

/// `geometry_msgs/msg/Twist`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Twist {
    /// Linear velocity, m/s.
    pub linear: Vector3,
    /// Angular velocity, rad/s.
    pub angular: Vector3,
}

/// A row-major 6x6 covariance, `float64[36]` (a fixed array: no length on
/// the wire; serde derives arrays up to 32 only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Covariance(pub [f64; 36]);

impl Default for Covariance {
    fn default() -> Self {
        Covariance([0.0; 36])
    }
}

impl Serialize for Covariance {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeTuple;
        let mut t = s.serialize_tuple(36)?;
        for x in &self.0 {
            t.serialize_element(x)?;
        }
        t.end()
    }
}

impl<'de> Deserialize<'de> for Covariance {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Covariance;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("36 floats")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<Covariance, A::Error> {
                let mut c = [0.0; 36];
                for (i, x) in c.iter_mut().enumerate() {
                    *x = a
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                Ok(Covariance(c))
            }
        }
        d.deserialize_tuple(36, V)
    }
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Row-major 6x6 covariance (x, y, z, rot x, rot y, rot z).
    pub covariance: Covariance,
}

/// `geometry_msgs/msg/TwistWithCovariance`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    /// The twist.
    pub twist: Twist,
    /// Row-major 6x6 covariance.
    pub covariance: Covariance,
}

/// `nav_msgs/msg/Odometry`: the pose in `header.frame_id`, the twist in
/// `child_frame_id` (the body).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    /// Stamp and the pose's frame.
    pub header: Header,
    /// The twist's frame (the body).
    pub child_frame_id: String,
    /// CoM pose.
    pub pose: PoseWithCovariance,
    /// CoM twist in `child_frame_id`.
    pub twist: TwistWithCovariance,
}

/// `sensor_msgs/msg/LaserScan`: ranges in the frame `header.frame_id`,
/// angles from its x axis (rad), ranges m (`+inf`: no return).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LaserScan {
    /// Stamp and sensor frame.
    pub header: Header,
    /// Angle of the first ray, rad.
    pub angle_min: f32,
    /// Angle of the last ray, rad.
    pub angle_max: f32,
    /// Angle between rays, rad.
    pub angle_increment: f32,
    /// Time between rays, s.
    pub time_increment: f32,
    /// Time between scans, s.
    pub scan_time: f32,
    /// Smallest valid range, m.
    pub range_min: f32,
    /// Largest valid range, m.
    pub range_max: f32,
    /// Ranges, m.
    pub ranges: Vec<f32>,
    /// Intensities.
    pub intensities: Vec<f32>,
}

/// `nav_msgs/msg/Path`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Path {
    /// Stamp and frame.
    pub header: Header,
    /// The poses in order.
    pub poses: Vec<PoseStamped>,
}

/// `std_msgs/msg/ColorRGBA`, each in `[0, 1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ColorRgba {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Alpha.
    pub a: f32,
}

/// `sensor_msgs/msg/CompressedImage` (only as a field of [`Marker`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Stamp and frame.
    pub header: Header,
    /// Image format.
    pub format: String,
    /// Image bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct UvCoordinate {
    /// u.
    pub u: f32,
    /// v.
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshFile {
    /// File name.
    pub filename: String,
    /// File bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker` (Jazzy layout, with the texture and mesh
/// fields added in Iron).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Stamp and frame.
    pub header: Header,
    /// Namespace.
    pub ns: String,
    /// Id within the namespace.
    pub id: i32,
    /// Marker type ([`Marker::LINE_STRIP`], ...).
    #[serde(rename = "type")]
    pub kind: i32,
    /// [`Marker::ADD`] or [`Marker::DELETEALL`].
    pub action: i32,
    /// Pose.
    pub pose: Pose,
    /// Scale, m.
    pub scale: Vector3,
    /// Color.
    pub color: ColorRgba,
    /// Lifetime (0: forever).
    pub lifetime: Duration,
    /// Follow the frame.
    pub frame_locked: bool,
    /// Points, m.
    pub points: Vec<Point>,
    /// Per-point colors.
    pub colors: Vec<ColorRgba>,
    /// Texture resource.
    pub texture_resource: String,
    /// Texture.
    pub texture: CompressedImage,
    /// Texture coordinates.
    pub uv_coordinates: Vec<UvCoordinate>,
    /// Text.
    pub text: String,
    /// Mesh resource.
    pub mesh_resource: String,
    /// Mesh file.
    pub mesh_file: MeshFile,
    /// Use the mesh's materials.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// `LINE_STRIP`.
    pub const LINE_STRIP: i32 = 4;
    /// `LINE_LIST`.
    pub const LINE_LIST: i32 = 5;
    /// `SPHERE_LIST`.
    pub const SPHERE_LIST: i32 = 7;
    /// `ADD`.
    pub const ADD: i32 = 0;
    /// `DELETEALL`.
    pub const DELETEALL: i32 = 3;
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MarkerArray {
    /// The markers.
    pub markers: Vec<Marker>,
}

/// `diagnostic_msgs/msg/KeyValue`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct KeyValue {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// `diagnostic_msgs/msg/DiagnosticStatus`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    /// 0 OK, 1 WARN, 2 ERROR, 3 STALE.
    pub level: u8,
    /// Name.
    pub name: String,
    /// Message.
    pub message: String,
    /// Hardware id.
    pub hardware_id: String,
    /// Values.
    pub values: Vec<KeyValue>,
}

/// `diagnostic_msgs/msg/DiagnosticArray`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    /// Stamp.
    pub header: Header,
    /// Statuses.
    pub status: Vec<DiagnosticStatus>,
}

/// `ldcbf_msgs/msg/GaitState` (`ros2/ldcbf_msgs/msg/GaitState.msg`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GaitState {
    /// Stamp and frame of `stance_foot`.
    pub header: Header,
    /// [`GaitState::LEFT`] or [`GaitState::RIGHT`].
    pub stance_side: u8,
    /// Stance foot position, m (z ignored).
    pub stance_foot: Point,
    /// Time already spent in the current step, s.
    pub time_in_step: f64,
    /// Turning rate in force, rad/s.
    pub turning_rate: f64,
}

impl GaitState {
    /// Left foot.
    pub const LEFT: u8 = 0;
    /// Right foot.
    pub const RIGHT: u8 = 1;
}

/// `ldcbf_msgs/msg/FootstepCommand` (`ros2/ldcbf_msgs/msg/FootstepCommand.msg`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FootstepCommand {
    /// Stamp (the gait state's) and frame.
    pub header: Header,
    /// [`FootstepCommand::SOLVED`] ... [`FootstepCommand::INFEASIBLE`].
    pub result: u8,
    /// `SOURCE_*`: the controller's `CommandSource`.
    pub source: u8,
    /// The controller's status name.
    pub status: String,
    /// Swing foot target, m.
    pub foot_target: Point,
    /// Turning rate of the next step, rad/s.
    pub turning_rate: f64,
    /// Planned stance feet `f_0 .. f_{N-1}`, m.
    pub planned_feet: Vec<Point>,
    /// Side of `f_0` ([`GaitState::LEFT`] or [`GaitState::RIGHT`]).
    pub first_side: u8,
    /// Predicted CoM `x_0 .. x_N`, m.
    pub predicted_com: Vec<Point>,
    /// Solver iterations.
    pub iterations: u32,
    /// Obstacles in the QP.
    pub active_obstacles: u8,
    /// Gait relaxation, m/s.
    pub relax_gait: f64,
    /// Safety relaxation, m.
    pub relax_safety: f64,
}

impl FootstepCommand {
    /// The QP was solved.
    pub const SOLVED: u8 = 0;
    /// Optimal with relaxed rows.
    pub const RELAXED: u8 = 1;
    /// Previous plan or capture step (solver budget or numerical failure).
    pub const FALLBACK: u8 = 2;
    /// Bad input: hold.
    pub const INVALID_INPUT: u8 = 3;
    /// Infeasible even relaxed: the fallback command.
    pub const INFEASIBLE: u8 = 4;
}
