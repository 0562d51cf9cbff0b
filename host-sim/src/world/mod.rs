//! The world the robot walks in, with nothing of the robot's own senses or
//! plans: the polygon type of every map, the robot's body and feet, the map's
//! R-tree, the occupancy grid of a known map, and the seeded map generators.
//! The lowest room: it depends on no other room of the crate.
//!
//! * [`robot`]: the robot's body disk and footprint (the `[robot]` table);
//! * [`obstacle_index`]: the known map's R-tree, so that a control cycle's
//!   cost does not grow with the map;
//! * [`grid`]: the occupancy grid of inflated obstacles, its distance
//!   transform, and whether a body fits from one point to another;
//! * [`random`]: the paper's seeded random convex obstacles and regular polygons;
//! * [`families`]: seeded layout families for a robot with a body (corridors,
//!   doorways, cups, wall starts, clutter, thin walls);
//! * [`people`]: seeded families with people who walk (crossing, head-on,
//!   crowd, a room crossed);
//! * [`moving`]: obstacles with a constant velocity, the true map at any time;
//! * [`crowd`]: people who walk to goals and react (ORCA, social force),
//!   and their seeded families (the crowd-navigation benchmark's among them).
//!
//! Frames and units: world frame W, metres, radians, as in the controller.

use ldcbf_controller::ConvexPolygon;
use ldcbf_controller::geometry::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;

pub mod crowd;
pub mod exact;
pub mod families;
pub mod grid;
pub mod moving;
pub mod obstacle_index;
pub mod people;
pub mod people_hard;
pub mod random;
pub mod robot;
pub mod setting;

/// Vertex capacity of scenario polygons.
pub const MAX_VERTICES: usize = 32;

/// The polygon type used by the simulator (world frame, metres).
pub type Polygon = ConvexPolygon<MAX_VERTICES>;

/// Signed distance from `p` to the nearest polygon, m (`+inf` if none).
pub fn clearance(p: &Vector2<f64>, obstacles: &[Polygon]) -> f64 {
    obstacles
        .iter()
        .map(|o| closest_point_point_polygon(p, o).signed_distance)
        .fold(f64::INFINITY, f64::min)
}

/// The square of half side `h` (m) around `c`, for tests.
#[cfg(test)]
pub(crate) fn square(c: [f64; 2], h: f64) -> Polygon {
    Polygon::new(&[
        [c[0] - h, c[1] - h],
        [c[0] + h, c[1] - h],
        [c[0] + h, c[1] + h],
        [c[0] - h, c[1] + h],
    ])
    .unwrap()
}
