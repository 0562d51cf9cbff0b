//! Obstacles that move: the true map at any time of a run.
//!
//! A scenario's obstacle may carry a constant velocity `v` (m/s, world frame
//! W; the `velocity` key of `[[obstacles]]`, or a family's people). At time
//! `t` (s, the plant's clock) it is its polygon at `t = 0` translated by
//! `v t`. Moving obstacles do not interact with anything: they pass through
//! walls, through each other and through the robot (contacts are counted,
//! not resolved: [`MovingMap::body_contacts`], [`MovingMap::foot_contacts`]).
//!
//! People who react ([`crate::world::crowd`]) are moved by the closed loop
//! instead ([`MovingMap::with_driven`], [`MovingMap::place`]): their
//! polygons and current velocities are whatever the crowd's state is.
//!
//! [`MovingMap`] holds the map at one time, [`MovingMap::set_time`] moves it,
//! and it answers the clearance questions of the 1 kHz loop against the true
//! positions: the obstacles at rest through an R-tree built once
//! ([`ObstacleIndex`]), the moving ones by a linear scan (a few people). With
//! no moving obstacle its answers are, bit for bit, those of the index over
//! the whole map.

use ldcbf_controller::geometry::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;

use crate::world::Polygon;
use crate::world::obstacle_index::ObstacleIndex;
use crate::world::robot::{CONTACT_TOLERANCE, RobotParams, signed_distance_convex};

/// Largest accepted obstacle speed, m/s (a running person is about 5 m/s).
pub const MAX_SPEED: f64 = 5.0;

/// Checks one obstacle velocity as written in a file (`[vx, vy]`, m/s):
/// exactly two finite numbers, speed at most [`MAX_SPEED`].
pub fn parse_velocity(v: &[f64]) -> Result<Vector2<f64>, String> {
    let [vx, vy] = v else {
        return Err(format!(
            "must be a list of exactly 2 numbers [vx, vy] (m/s, world frame), got {}",
            v.len()
        ));
    };
    if !(vx.is_finite() && vy.is_finite()) {
        return Err("vx and vy must be finite".into());
    }
    let v = Vector2::new(*vx, *vy);
    if v.norm() > MAX_SPEED {
        return Err(format!(
            "speed {:.3} m/s is above {MAX_SPEED} m/s",
            v.norm()
        ));
    }
    Ok(v)
}

/// `poly` translated by `d` (m). A translation keeps a convex polygon convex;
/// should rounding make a nearly collinear corner fail the convexity test, the
/// hull of the moved vertices is taken (the same polygon up to rounding).
pub fn translated(poly: &Polygon, d: Vector2<f64>) -> Polygon {
    let v: Vec<[f64; 2]> = poly
        .vertices()
        .iter()
        .map(|p| [p.x + d.x, p.y + d.y])
        .collect();
    Polygon::new(&v)
        .or_else(|_| Polygon::hull(&v))
        .unwrap_or(*poly)
}

/// The mean of a polygon's vertices, m (world frame).
pub fn vertex_centre(p: &Polygon) -> Vector2<f64> {
    p.vertices().iter().sum::<Vector2<f64>>() / p.len().max(1) as f64
}

/// One obstacle that overlaps a part of the robot, at the current time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    /// Index of the obstacle in the scenario's list.
    pub obstacle: usize,
    /// The part's signed clearance to it, m (below `-CONTACT_TOLERANCE`).
    pub clearance: f64,
    /// Unit normal from the obstacle towards the part (world frame): the
    /// direction in which the part would leave the obstacle.
    pub normal: Vector2<f64>,
}

/// The true map at one time: every obstacle at its current position.
#[derive(Clone, Debug)]
pub struct MovingMap {
    initial: Vec<Polygon>,
    velocities: Vec<Vector2<f64>>,
    /// Indices of the obstacles with a non-zero velocity.
    moving: Vec<usize>,
    /// Indices (in the scenario's list) of the obstacles at rest, and those
    /// obstacles, in the order the index was built from.
    rest_ids: Vec<usize>,
    rest: Vec<Polygon>,
    rest_index: ObstacleIndex,
    current: Vec<Polygon>,
    time: f64,
    /// Obstacles from this index on are placed by the caller.
    driven_from: usize,
}

impl MovingMap {
    /// The map at `t = 0`: `obstacles` (world frame, at `t = 0`) and their
    /// `velocities` (m/s; a shorter list leaves the rest at rest). `Err` if
    /// the index cannot hold the map.
    pub fn new(obstacles: &[Polygon], velocities: &[Vector2<f64>]) -> Result<Self, String> {
        Self::with_driven(obstacles, velocities, obstacles.len())
    }

    /// [`MovingMap::new`] where the obstacles from index `driven_from` on
    /// are moved by the caller ([`MovingMap::place`]: people who react,
    /// [`crate::world::crowd`]) rather than by their velocities, and count
    /// as moving whatever their velocity.
    pub fn with_driven(
        obstacles: &[Polygon],
        velocities: &[Vector2<f64>],
        driven_from: usize,
    ) -> Result<Self, String> {
        let velocities: Vec<Vector2<f64>> = (0..obstacles.len())
            .map(|i| velocities.get(i).copied().unwrap_or_else(Vector2::zeros))
            .collect();
        let moves = |i: usize| i >= driven_from || velocities[i] != Vector2::zeros();
        let moving: Vec<usize> = (0..obstacles.len()).filter(|&i| moves(i)).collect();
        let rest_ids: Vec<usize> = (0..obstacles.len()).filter(|&i| !moves(i)).collect();
        let rest: Vec<Polygon> = rest_ids.iter().map(|&i| obstacles[i]).collect();
        Ok(MovingMap {
            rest_index: ObstacleIndex::new(&rest)?,
            initial: obstacles.to_vec(),
            velocities,
            moving,
            rest_ids,
            rest,
            current: obstacles.to_vec(),
            time: 0.0,
            driven_from,
        })
    }

    /// No obstacle moves.
    pub fn is_static(&self) -> bool {
        self.moving.is_empty()
    }

    /// Moves every moving obstacle to its position at time `t` (s) (those
    /// placed by the caller stay where [`MovingMap::place`] put them).
    pub fn set_time(&mut self, t: f64) {
        self.time = t;
        for &i in &self.moving {
            if i < self.driven_from {
                self.current[i] = translated(&self.initial[i], self.velocities[i] * t);
            }
        }
    }

    /// Puts the caller-driven obstacle `i` at its initial polygon moved by
    /// `shift` (m), with velocity `velocity` (m/s). Ignored for an obstacle
    /// not driven by the caller.
    pub fn place(&mut self, i: usize, shift: Vector2<f64>, velocity: Vector2<f64>) {
        if i >= self.driven_from && i < self.current.len() {
            self.current[i] = translated(&self.initial[i], shift);
            self.velocities[i] = velocity;
        }
    }

    /// The time of the current positions, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Every obstacle at the current time, in the scenario's order.
    pub fn obstacles(&self) -> &[Polygon] {
        &self.current
    }

    /// Every obstacle's velocity, m/s (zero at rest), in the scenario's order.
    pub fn velocities(&self) -> &[Vector2<f64>] {
        &self.velocities
    }

    /// The obstacles at rest, in the scenario's order (what a planner of the
    /// static map sees).
    pub fn rest_obstacles(&self) -> &[Polygon] {
        &self.rest
    }

    /// The index over the obstacles at rest (the whole map when
    /// [`MovingMap::is_static`]: then its indices are the scenario's).
    pub fn rest_index(&self) -> &ObstacleIndex {
        &self.rest_index
    }

    /// Signed distance from `p` (m) to the nearest obstacle at the current
    /// time, m (negative inside; `+inf` without obstacles).
    pub fn clearance(&self, p: &Vector2<f64>) -> f64 {
        self.moving
            .iter()
            .map(|&i| closest_point_point_polygon(p, &self.current[i]).signed_distance)
            .fold(self.rest_index.clearance(p, &self.rest), f64::min)
    }

    /// The footprint's signed clearance to the nearest obstacle at the
    /// current time, m ([`RobotParams::foot_clearance`]).
    pub fn foot_clearance(&self, robot: &RobotParams, center: Vector2<f64>, heading: f64) -> f64 {
        let foot = robot.footprint(center, heading);
        self.moving
            .iter()
            .map(|&i| signed_distance_convex(&foot, &self.current[i]))
            .fold(
                self.rest_index
                    .foot_clearance(robot, center, heading, &self.rest),
                f64::min,
            )
    }

    /// The obstacles that overlap the body disk of radius `radius` (m) around
    /// the CoM `p` (body clearance below `-CONTACT_TOLERANCE`), into `out`
    /// (cleared first), by increasing obstacle index.
    pub fn body_contacts(&self, p: &Vector2<f64>, radius: f64, out: &mut Vec<Overlap>) {
        out.clear();
        let mut near = Vec::new();
        self.rest_index.within_into(p, radius, &mut near);
        let ids = near
            .iter()
            .map(|&j| self.rest_ids[j as usize])
            .chain(self.moving.iter().copied());
        for i in ids {
            let c = closest_point_point_polygon(p, &self.current[i]);
            let clearance = c.signed_distance - radius;
            if clearance < -CONTACT_TOLERANCE {
                let d = p - c.point;
                let toward = if c.signed_distance < 0.0 { -d } else { d };
                out.push(Overlap {
                    obstacle: i,
                    clearance,
                    normal: unit_or(toward, -self.velocities[i]),
                });
            }
        }
        out.sort_by_key(|o| o.obstacle);
    }

    /// The obstacles that overlap the footprint at `center`, `heading` (by
    /// more than `CONTACT_TOLERANCE`), into `out` (cleared first), by
    /// increasing obstacle index; the normal points from the obstacle's
    /// centre of vertices to the foot's centre.
    pub fn foot_contacts(
        &self,
        robot: &RobotParams,
        center: Vector2<f64>,
        heading: f64,
        out: &mut Vec<Overlap>,
    ) {
        out.clear();
        let foot = robot.footprint(center, heading);
        let reach = foot.iter().map(|c| (c - center).norm()).fold(0.0, f64::max);
        let mut near = Vec::new();
        self.rest_index.within_into(&center, reach, &mut near);
        let ids = near
            .iter()
            .map(|&j| self.rest_ids[j as usize])
            .chain(self.moving.iter().copied());
        for i in ids {
            let o = &self.current[i];
            let clearance = signed_distance_convex(&foot, o);
            if clearance < -CONTACT_TOLERANCE {
                out.push(Overlap {
                    obstacle: i,
                    clearance,
                    normal: unit_or(center - vertex_centre(o), -self.velocities[i]),
                });
            }
        }
        out.sort_by_key(|o| o.obstacle);
    }
}

/// `v / |v|`, or `fallback / |fallback|` when `v` is (nearly) zero, or +x.
fn unit_or(v: Vector2<f64>, fallback: Vector2<f64>) -> Vector2<f64> {
    if v.norm() > 1e-12 {
        v / v.norm()
    } else if fallback.norm() > 1e-12 {
        fallback / fallback.norm()
    } else {
        Vector2::x()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::square;

    #[test]
    fn velocity_is_two_finite_numbers_within_the_limit() {
        assert_eq!(parse_velocity(&[0.3, -0.4]), Ok(Vector2::new(0.3, -0.4)));
        assert!(parse_velocity(&[1.0]).unwrap_err().contains("exactly 2"));
        assert!(
            parse_velocity(&[1.0, 2.0, 3.0])
                .unwrap_err()
                .contains("exactly 2")
        );
        assert!(
            parse_velocity(&[f64::NAN, 0.0])
                .unwrap_err()
                .contains("finite")
        );
        assert!(
            parse_velocity(&[f64::INFINITY, 0.0])
                .unwrap_err()
                .contains("finite")
        );
        assert!(
            parse_velocity(&[4.0, 3.0001])
                .unwrap_err()
                .contains("above 5")
        );
        assert!(
            parse_velocity(&[4.0, 3.0]).is_ok(),
            "exactly 5 m/s is accepted"
        );
    }

    #[test]
    fn a_moving_polygon_is_its_initial_one_moved_by_v_t() {
        let obstacles = [square([0.0, 0.0], 0.5), square([5.0, 0.0], 0.5)];
        let mut map = MovingMap::new(&obstacles, &[Vector2::new(1.0, -0.5)]).unwrap();
        assert!(!map.is_static());
        map.set_time(2.0);
        assert_eq!(map.obstacles()[0], square([2.0, -1.0], 0.5));
        assert_eq!(map.obstacles()[1], obstacles[1], "the second is at rest");
        let p = Vector2::new(2.0, 1.0);
        assert!((map.clearance(&p) - 1.5).abs() < 1e-12);
        let mut out = Vec::new();
        map.body_contacts(&Vector2::new(2.0, -0.7), 0.25, &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].obstacle, 0);
        // The CoM is inside, 0.2 m from the top side: out through the top.
        assert!((out[0].normal - Vector2::new(0.0, 1.0)).norm() < 1e-12);
        assert!((out[0].clearance - (-0.2 - 0.25)).abs() < 1e-12);
        map.body_contacts(&Vector2::new(5.0, 0.8), 0.25, &mut out);
        assert!(out.is_empty(), "0.3 m from the square at rest, body 0.25 m");
        map.body_contacts(&Vector2::new(5.0, 0.7), 0.25, &mut out);
        assert_eq!(out[0].obstacle, 1);
    }

    #[test]
    fn a_static_map_answers_as_the_index_over_the_whole_map() {
        let obstacles = [
            square([0.0, 0.0], 0.5),
            square([3.0, 1.0], 0.2),
            square([-2.0, 4.0], 1.0),
        ];
        let map = MovingMap::new(&obstacles, &[]).unwrap();
        let index = ObstacleIndex::new(&obstacles).unwrap();
        let robot = RobotParams::default();
        for k in 0..200 {
            let p = Vector2::new(-3.0 + 0.037 * k as f64, -1.0 + 0.029 * k as f64);
            assert_eq!(map.clearance(&p), index.clearance(&p, &obstacles));
            let h = 0.1 * k as f64;
            assert_eq!(
                map.foot_clearance(&robot, p, h),
                index.foot_clearance(&robot, p, h, &obstacles)
            );
        }
    }

    #[test]
    fn foot_contacts_find_a_person_on_the_foot() {
        let robot = RobotParams::default();
        let person = square([1.0, 0.0], 0.2);
        let mut map = MovingMap::new(&[person], &[Vector2::new(-0.5, 0.0)]).unwrap();
        let mut out = Vec::new();
        map.foot_contacts(&robot, Vector2::zeros(), 0.0, &mut out);
        assert!(out.is_empty());
        map.set_time(1.5); // the square's centre at x = 0.25: over the toe
        map.foot_contacts(&robot, Vector2::zeros(), 0.0, &mut out);
        assert_eq!(out.len(), 1);
        assert!(out[0].normal.x < 0.0, "the foot is behind the person");
    }
}
