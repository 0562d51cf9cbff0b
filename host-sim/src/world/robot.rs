//! The robot's body and feet: the scenario's `[robot]` table.
//!
//! The controller's barrier keeps a body DISK (radius `body_radius` around the
//! CoM, horizontal plane) out of every obstacle, and, with `keep_feet_clear`,
//! every footstep's FOOTPRINT (a `foot_length` x `foot_width` rectangle centred
//! on the footstep, long side along the heading at landing) off them. The
//! simulator measures the clearance of those shapes against the TRUE map, not
//! of the point CoM ([`crate::report`]).
//!
//! Defaults are an adult-size humanoid:
//!
//! * `body_radius = 0.25` m: a 0.5 m wide envelope, the shoulder breadth of an
//!   adult (about 0.40-0.46 m in anthropometric surveys such as ANSUR II) with
//!   room for the arms' swing. Humanoids built for human spaces (Digit, H1,
//!   Atlas) are of that width.
//! * `foot_length = 0.22`, `foot_width = 0.10` m: a human-size sole; a
//!   Digit-like robot foot is smaller, so this is on the safe side.
//!
//! The paper's and the report's reproductions set all three to 0 (a point CoM,
//! point feet) and say so in their file's `note`, so their figures stay
//! comparable with the sources.

use ldcbf_controller::Config;
use ldcbf_controller::geometry::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::world::Polygon;
use crate::world::setting::SettingError;

/// Contact tolerance, m: a clearance below `-CONTACT_TOLERANCE` is a collision.
/// A barrier or foot row that is active holds to rounding (`1e-14` m), so a
/// shape that touches an obstacle exactly is not counted as overlapping it.
pub const CONTACT_TOLERANCE: f64 = 1e-9;

/// The `[robot]` table. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotParams {
    /// Radius of the body disk around the CoM, m (>= 0; 0 = a point CoM).
    pub body_radius: f64,
    /// Footprint length along the heading, m (>= 0).
    pub foot_length: f64,
    /// Footprint width across the heading, m (>= 0).
    pub foot_width: f64,
    /// Keep every footstep's footprint off the obstacles: the controller's
    /// foot-clearance rows (`controller.foot_clearance`, default 0 m of extra
    /// clearance). `false` = the paper's QP, no foot rows (and then the
    /// continuous CoM path between step ends is not guaranteed, only the step
    /// ends: [`ldcbf_controller::Config::barrier_margin`]).
    pub keep_feet_clear: bool,
}

impl Default for RobotParams {
    fn default() -> Self {
        RobotParams {
            body_radius: 0.25,
            foot_length: 0.22,
            foot_width: 0.10,
            keep_feet_clear: true,
        }
    }
}

impl RobotParams {
    /// A point robot with point feet and no foot rows (the paper's model).
    pub const POINT: RobotParams = RobotParams {
        body_radius: 0.0,
        foot_length: 0.0,
        foot_width: 0.0,
        keep_feet_clear: false,
    };

    /// Checks every field: the error names it and says what it must satisfy.
    pub fn validate(&self) -> Result<(), SettingError> {
        let ok = |v: f64, hi: f64| v.is_finite() && (0.0..=hi).contains(&v);
        if !ok(self.body_radius, 5.0) {
            return Err(SettingError::new("body_radius", "must be in [0, 5] m"));
        }
        if !ok(self.foot_length, 1.0) {
            return Err(SettingError::new("foot_length", "must be in [0, 1] m"));
        }
        if !ok(self.foot_width, 1.0) {
            return Err(SettingError::new("foot_width", "must be in [0, 1] m"));
        }
        Ok(())
    }

    /// `config` with the body and feet of this robot: `body_radius`,
    /// `foot_length`, `foot_width`, and the foot rows on (`foot_clearance`
    /// kept when the file set it, else 0) or off.
    pub fn apply(&self, config: Config) -> Config {
        Config {
            body_radius: self.body_radius,
            foot_length: self.foot_length,
            foot_width: self.foot_width,
            foot_clearance: if self.keep_feet_clear {
                Some(config.foot_clearance.unwrap_or(0.0))
            } else {
                None
            },
            ..config
        }
    }

    /// Half-diagonal of the footprint, m: the radius of the disk that holds
    /// the foot whatever its orientation.
    pub fn foot_reach(&self) -> f64 {
        0.5 * self.foot_length.hypot(self.foot_width)
    }

    /// The four corners of the footprint of a foot at `center` (m, world)
    /// whose long axis points along `heading` (rad), counter-clockwise.
    pub fn footprint(&self, center: Vector2<f64>, heading: f64) -> [Vector2<f64>; 4] {
        let along = Vector2::new(heading.cos(), heading.sin()) * (0.5 * self.foot_length);
        let across = Vector2::new(-heading.sin(), heading.cos()) * (0.5 * self.foot_width);
        [
            center - along - across,
            center + along - across,
            center + along + across,
            center - along + across,
        ]
    }

    /// Signed clearance of the footprint at `center`, `heading` to the nearest
    /// of `obstacles`, m: the distance between the two shapes when apart,
    /// minus the penetration depth when they overlap; `+inf` without obstacles.
    pub fn foot_clearance(&self, center: Vector2<f64>, heading: f64, obstacles: &[Polygon]) -> f64 {
        let foot = self.footprint(center, heading);
        obstacles
            .iter()
            .map(|o| signed_distance_convex(&foot, o))
            .fold(f64::INFINITY, f64::min)
    }

    /// Signed clearance of the body disk to the nearest obstacle, m (negative =
    /// the body overlaps an obstacle), from the CoM's signed distance to it.
    pub fn body_clearance(&self, com_clearance: f64) -> f64 {
        com_clearance - self.body_radius
    }
}

/// Signed distance between a convex quadrilateral `a` (possibly degenerate: a
/// segment or a point, corners counter-clockwise) and the convex polygon `b`,
/// m: the gap when they are apart; when they overlap, minus the smallest
/// translation that separates them (the least overlap of their projections on
/// the edge normals of both, the separating axis theorem).
pub fn signed_distance_convex(a: &[Vector2<f64>; 4], b: &Polygon) -> f64 {
    let bv = b.vertices();
    // Separation axes: the edge normals of both shapes (degenerate edges skipped).
    let mut depth = f64::INFINITY;
    let mut separated = false;
    let edges_a = (0..4).map(|i| (a[i], a[(i + 1) % 4]));
    let edges_b = (0..bv.len()).map(|i| (bv[i], bv[(i + 1) % bv.len()]));
    for (p, q) in edges_a.chain(edges_b) {
        let d = q - p;
        let len = d.norm();
        if len < 1e-12 {
            continue;
        }
        let n = Vector2::new(d.y, -d.x) / len;
        let (amin, amax) = project(a.iter(), &n);
        let (bmin, bmax) = project(bv.iter(), &n);
        let overlap = (amax - bmin).min(bmax - amin);
        if overlap <= 0.0 {
            separated = true;
            break;
        }
        depth = depth.min(overlap);
    }
    if !separated && depth.is_finite() {
        return -depth;
    }
    // Apart (or `a` is a point or a segment): the least vertex-to-shape distance.
    let from_a = a
        .iter()
        .map(|v| closest_point_point_polygon(v, b).signed_distance)
        .fold(f64::INFINITY, f64::min);
    if from_a <= 0.0 {
        return from_a;
    }
    let from_b = bv
        .iter()
        .flat_map(|v| (0..4).map(move |i| distance_point_segment(v, &a[i], &a[(i + 1) % 4])))
        .fold(f64::INFINITY, f64::min);
    from_a.min(from_b)
}

fn project<'a>(points: impl Iterator<Item = &'a Vector2<f64>>, n: &Vector2<f64>) -> (f64, f64) {
    points.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
        let t = p.dot(n);
        (lo.min(t), hi.max(t))
    })
}

fn distance_point_segment(p: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    let d = b - a;
    let l2 = d.norm_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(&d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::square;

    #[test]
    fn foot_clearance_is_the_gap_or_minus_the_depth() {
        let r = RobotParams::default(); // foot 0.22 x 0.10
        let obs = [square([1.0, 0.0], 0.5)]; // x in [0.5, 1.5]
        // Heading along x: the foot's tip at x = c + 0.11.
        let gap = r.foot_clearance(Vector2::new(0.2, 0.0), 0.0, &obs);
        assert!((gap - (0.5 - 0.31)).abs() < 1e-12, "{gap}");
        // Across: the foot's side at x = c + 0.05.
        let gap = r.foot_clearance(Vector2::new(0.2, 0.0), core::f64::consts::FRAC_PI_2, &obs);
        assert!((gap - (0.5 - 0.25)).abs() < 1e-12, "{gap}");
        // Overlapping by 0.04 m along x.
        let pen = r.foot_clearance(Vector2::new(0.43, 0.0), 0.0, &obs);
        assert!((pen + 0.04).abs() < 1e-12, "{pen}");
        // Diagonal gap: corner to corner.
        let obs = [square([1.0, 1.0], 0.5)];
        let d = r.foot_clearance(Vector2::new(0.0, 0.0), 0.0, &obs);
        assert!((d - (0.5f64 - 0.11).hypot(0.5 - 0.05)).abs() < 1e-12, "{d}");
        // A point foot is the point's signed distance.
        let d = RobotParams::POINT.foot_clearance(Vector2::new(0.7, 1.0), 0.3, &obs);
        assert!((d + 0.2).abs() < 1e-12, "{d}");
    }

    #[test]
    fn apply_sets_body_and_feet() {
        let c = RobotParams::default().apply(Config::default());
        assert_eq!(c.body_radius, 0.25);
        assert_eq!(c.foot_clearance, Some(0.0));
        let with = Config {
            foot_clearance: Some(0.05),
            ..Config::default()
        };
        assert_eq!(
            RobotParams::default().apply(with).foot_clearance,
            Some(0.05)
        );
        assert_eq!(RobotParams::POINT.apply(with).foot_clearance, None);
        assert_eq!(RobotParams::POINT.apply(with).body_radius, 0.0);
    }

    #[test]
    fn validate_names_the_field() {
        let bad = RobotParams {
            foot_width: -0.1,
            ..RobotParams::default()
        };
        assert_eq!(bad.validate().unwrap_err().field, "foot_width");
        let bad = RobotParams {
            body_radius: f64::NAN,
            ..RobotParams::default()
        };
        assert_eq!(bad.validate().unwrap_err().field, "body_radius");
    }
}
