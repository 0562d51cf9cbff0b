//! Contacts between the robot and the obstacles at 1 kHz, and who moved into
//! whom.
//!
//! A **contact** is an episode: it starts at the first tick at which a part
//! of the robot overlaps an obstacle by more than
//! [`CONTACT_TOLERANCE`](crate::world::robot::CONTACT_TOLERANCE) and lasts
//! while it does. The parts are the body disk (radius `robot.body_radius`
//! around the CoM) and the stance foot's footprint (from the tick it lands to
//! the tick the next foot lands), both against the obstacles' TRUE positions
//! at that tick ([`MovingMap`]). Each contact is classified once, at its start:
//!
//! * **robot moved into the obstacle** ([`ContactCause::Robot`]), a controller
//!   failure, when
//!   * the obstacle is at rest, or
//!   * it is the body, and the robot was walking toward the obstacle: the
//!     robot's mean CoM velocity over the last step duration `T` (the CoM
//!     displacement over the last `T` seconds divided by `T`, which removes the
//!     pendulum's sway within a step), projected on the unit normal from the
//!     obstacle to the body, is below `-`[`STANDING_SPEED`] (the robot
//!     approached at more than 5 cm/s), or
//!   * it is a foot that landed on the obstacle (the contact starts at the
//!     landing tick: the controller chose that foothold);
//! * **obstacle moved into a standing robot** ([`ContactCause::Obstacle`])
//!   otherwise: a moving obstacle (a person) walked into a body that was
//!   standing, moving away, or moving across (approach at most 5 cm/s), or
//!   onto a foot already planted.
//!
//! The robot's standing policy toward a person who walks into it is the
//! controller's: with the obstacles' velocities the barrier at each horizon
//! step keeps the body and the feet off the person's predicted position, so
//! the MPC steps aside or back while that is feasible within the gait limits;
//! when it is not (a person faster than the robot's backward speed, or coming
//! from two sides), the priority scheme relaxes the barrier and the contact
//! counts as the person's.

use ldcbf_controller::nalgebra::Vector2;
use serde::Serialize;

use crate::sim::Sample;
use crate::world::moving::{MovingMap, Overlap};
use crate::world::robot::RobotParams;

/// Approach speed below which the robot counts as standing (not moving toward
/// an obstacle), m/s.
pub const STANDING_SPEED: f64 = 0.05;

/// Which part of the robot touched the obstacle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactPart {
    /// The body disk around the CoM.
    Body,
    /// The stance foot's footprint.
    Foot,
}

/// Who moved into whom (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactCause {
    /// The robot moved into the obstacle: a controller failure.
    Robot,
    /// A moving obstacle moved into a robot that was not moving toward it.
    Obstacle,
}

/// One contact episode, as classified at its first tick.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Contact {
    /// Time of its first tick, s.
    pub time: f64,
    /// Index of the obstacle in the scenario's list.
    pub obstacle: usize,
    /// The part that touched it.
    pub part: ContactPart,
    /// Who moved into whom.
    pub cause: ContactCause,
    /// The robot's approach speed toward the obstacle at the start (mean CoM
    /// velocity over the last step, along the normal into the obstacle), m/s
    /// (0 for a planted foot).
    pub robot_approach: f64,
    /// The obstacle's approach speed toward the part, m/s.
    pub obstacle_approach: f64,
}

/// Follows the contacts of one run, tick by tick.
#[derive(Clone, Debug, Default)]
pub(crate) struct ContactMonitor {
    body: Vec<usize>,
    foot: Vec<usize>,
    scratch: Vec<Overlap>,
    /// Every contact so far, in order of their start.
    pub(crate) contacts: Vec<Contact>,
}

/// The mean CoM velocity over the last `ticks` plant ticks of `samples`
/// (1 kHz, m/s; over all of them when fewer; zero with fewer than two).
pub(crate) fn mean_velocity(samples: &[Sample], ticks: usize) -> Vector2<f64> {
    let (Some(first), Some(last)) = (
        samples.get(samples.len().saturating_sub(ticks + 1)),
        samples.last(),
    ) else {
        return Vector2::zeros();
    };
    let dt = last.time - first.time;
    if dt > 0.0 {
        (last.position - first.position) / dt
    } else {
        Vector2::zeros()
    }
}

impl ContactMonitor {
    /// Looks at one tick: the body at `com` (m) with mean velocity `walk`
    /// (m/s, [`mean_velocity`]), the stance foot at `foot` (m) with heading
    /// `foot_heading` (rad), `landed` when that foot landed at this tick (or
    /// is the initial stance foot at the first tick).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn observe(
        &mut self,
        map: &MovingMap,
        robot: &RobotParams,
        time: f64,
        com: Vector2<f64>,
        walk: Vector2<f64>,
        foot: Vector2<f64>,
        foot_heading: f64,
        landed: bool,
    ) {
        map.body_contacts(&com, robot.body_radius, &mut self.scratch);
        let body_now: Vec<usize> = self.scratch.iter().map(|o| o.obstacle).collect();
        for o in &self.scratch {
            if self.body.contains(&o.obstacle) {
                continue;
            }
            let v_obs = map.velocities()[o.obstacle];
            let robot_approach = -walk.dot(&o.normal);
            let obstacle_approach = v_obs.dot(&o.normal);
            let cause = if v_obs == Vector2::zeros() || robot_approach > STANDING_SPEED {
                ContactCause::Robot
            } else {
                ContactCause::Obstacle
            };
            self.contacts.push(Contact {
                time,
                obstacle: o.obstacle,
                part: ContactPart::Body,
                cause,
                robot_approach,
                obstacle_approach,
            });
        }
        self.body = body_now;
        if landed {
            self.foot.clear();
        }
        map.foot_contacts(robot, foot, foot_heading, &mut self.scratch);
        let foot_now: Vec<usize> = self.scratch.iter().map(|o| o.obstacle).collect();
        for o in &self.scratch {
            if self.foot.contains(&o.obstacle) {
                continue;
            }
            let v_obs = map.velocities()[o.obstacle];
            let cause = if landed || v_obs == Vector2::zeros() {
                ContactCause::Robot
            } else {
                ContactCause::Obstacle
            };
            self.contacts.push(Contact {
                time,
                obstacle: o.obstacle,
                part: ContactPart::Foot,
                cause,
                robot_approach: 0.0,
                obstacle_approach: v_obs.dot(&o.normal),
            });
        }
        self.foot = foot_now;
    }
}

/// `(robot moved into an obstacle, obstacle moved into a standing robot)`:
/// the number of contacts of each cause.
pub fn contact_counts(contacts: &[Contact]) -> (usize, usize) {
    let robot = contacts
        .iter()
        .filter(|c| c.cause == ContactCause::Robot)
        .count();
    (robot, contacts.len() - robot)
}
