//! Messages the node's tests send.

use ldcbf_ros2::msgs::{GaitState, Header, Point, Pose, PoseStamped, Time};

/// A gait state stamped `stamp` in `map`: left stance at `foot` (m), 0.1 s
/// into the step, not turning.
pub fn gait_at(stamp: Time, foot: [f64; 2]) -> GaitState {
    GaitState {
        header: Header {
            stamp,
            frame_id: "map".into(),
        },
        stance_side: GaitState::LEFT,
        stance_foot: Point {
            x: foot[0],
            y: foot[1],
            z: 0.0,
        },
        time_in_step: 0.1,
        turning_rate: 0.0,
    }
}

/// A goal at (`x`, `y`), m.
pub fn goal(x: f64, y: f64) -> PoseStamped {
    PoseStamped {
        pose: Pose {
            position: Point { x, y, z: 0.0 },
            ..Pose::default()
        },
        ..PoseStamped::default()
    }
}
