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
//!     landing tick: the controller chose that foothold), unless the obstacle
//!     is a person who overlaps the body at that tick: the landing then takes
//!     the cause of that body contact (see below);
//! * **obstacle moved into a standing robot** ([`ContactCause::Obstacle`])
//!   otherwise: a moving obstacle (a person) walked into a body that was
//!   standing, moving away, or moving across (approach at most 5 cm/s), or
//!   onto a foot already planted.
//!
//! **A foot landing on a person inside the body.** A person who overlaps the
//! body disk covers ground next to the CoM, where every foothold within
//! reach of the swing foot may lie; a landing on them is part of the body
//! contact already under way, and is counted with its cause: the person's
//! when the person walked into the body, the robot's when the robot walked
//! into the person. A landing on a person who is clear of the body at the
//! landing tick stays the robot's, however the person moved during the
//! swing: the people walk at constant velocity and the controller plans
//! every foothold against their predicted positions, so such a landing is a
//! controller failure (`docs/results.md`, "Moving obstacles").
//!
//! **People who react** ([`crate::world::crowd`]: ORCA, social force,
//! constant velocity toward a goal, stops) are classified by the same rule,
//! with the person's velocity at the contact's first tick (their current
//! velocity in the map, [`MovingMap::place`], not a constant one): a person
//! who stands at that tick (during a stop, or at the goal) counts as an
//! obstacle at rest, so the contact is the robot's; a person who walks into
//! a robot that stands, moves away or moves across is the person's. Whether
//! the person sees the robot does not change the rule: a person who does
//! not see it may walk into it, and that contact is the person's unless
//! the robot was moving toward them.
//!
//! The robot's policy toward a person who walks into it is the controller's
//! (`controller/src/mpc/give_way.rs`, docs/safety.md): near people it walks no
//! faster than it can stop in one step, the barrier at each horizon step keeps
//! the body and the feet off the person's predicted position, so the MPC
//! steps aside or back while that is feasible within the gait limits; when it
//! is not (a person faster than the robot's backward speed, or coming from
//! two sides), the priority scheme relaxes the barrier while planning away
//! from the people in the conflict, and the contact counts as the person's
//! unless the robot was still moving toward them.

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
    /// The obstacles overlapping the body, each with the cause of its
    /// episode.
    body: Vec<(usize, ContactCause)>,
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
        let mut body_now = Vec::with_capacity(self.scratch.len());
        for o in &self.scratch {
            if let Some(&(_, cause)) = self.body.iter().find(|b| b.0 == o.obstacle) {
                body_now.push((o.obstacle, cause));
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
            body_now.push((o.obstacle, cause));
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
            let cause = if v_obs == Vector2::zeros() {
                ContactCause::Robot
            } else if landed {
                // A landing on a person over the body takes that contact's cause.
                self.body
                    .iter()
                    .find(|b| b.0 == o.obstacle)
                    .map_or(ContactCause::Robot, |&(_, body_cause)| body_cause)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Polygon;
    use crate::world::random::regular_polygon;

    fn person(x: f64, y: f64) -> Polygon {
        Polygon::new(&regular_polygon([x, y], 0.25, 8, 0.0)).unwrap()
    }

    /// The monitor after one tick at time `t`, the body at `com` walking at
    /// `walk`, the stance foot far away (so only the body can touch).
    fn body_tick(
        m: &mut ContactMonitor,
        map: &mut MovingMap,
        t: f64,
        com: [f64; 2],
        walk: [f64; 2],
    ) {
        map.set_time(t);
        let robot = RobotParams::default();
        m.observe(
            map,
            &robot,
            t,
            Vector2::new(com[0], com[1]),
            Vector2::new(walk[0], walk[1]),
            Vector2::new(-50.0, 0.0),
            0.0,
            false,
        );
    }

    #[test]
    fn a_person_walking_into_a_standing_robot_is_the_persons_contact() {
        // The person starts 1 m to the right and walks left at 0.5 m/s.
        let mut map = MovingMap::new(&[person(1.0, 0.0)], &[Vector2::new(-0.5, 0.0)]).unwrap();
        let mut m = ContactMonitor::default();
        for k in 0..2000 {
            body_tick(&mut m, &mut map, k as f64 * 1e-3, [0.0, 0.0], [0.0, 0.0]);
        }
        assert_eq!(
            m.contacts.len(),
            1,
            "one episode, however long: {:?}",
            m.contacts
        );
        let c = m.contacts[0];
        assert_eq!(
            (c.part, c.cause),
            (ContactPart::Body, ContactCause::Obstacle)
        );
        assert!((c.obstacle_approach - 0.5).abs() < 0.05, "{c:?}");
        // Body 0.25 + person ~0.25 (the octagon's inradius 0.231): contact
        // after about (1 - 0.48) / 0.5 = 1.04 s.
        assert!((1.0..1.1).contains(&c.time), "{c:?}");
        assert_eq!(contact_counts(&m.contacts), (0, 1));
    }

    #[test]
    fn walking_toward_an_obstacle_is_the_robots_contact() {
        // The same person, but the robot walks toward them at 0.3 m/s.
        let mut map = MovingMap::new(&[person(1.0, 0.0)], &[Vector2::new(-0.5, 0.0)]).unwrap();
        let mut m = ContactMonitor::default();
        for k in 0..2000 {
            let t = k as f64 * 1e-3;
            body_tick(&mut m, &mut map, t, [0.3 * t, 0.0], [0.3, 0.0]);
        }
        assert_eq!(contact_counts(&m.contacts), (1, 0), "{:?}", m.contacts);
        assert!((m.contacts[0].robot_approach - 0.3).abs() < 0.05);
        // A wall at rest: the robot's, whatever its speed.
        let mut map = MovingMap::new(&[person(0.4, 0.0)], &[]).unwrap();
        let mut m = ContactMonitor::default();
        body_tick(&mut m, &mut map, 0.0, [0.0, 0.0], [0.0, 0.0]);
        assert_eq!(contact_counts(&m.contacts), (1, 0));
    }

    #[test]
    fn a_robot_backing_away_from_a_faster_person_is_not_at_fault() {
        let mut map = MovingMap::new(&[person(1.0, 0.0)], &[Vector2::new(-0.8, 0.0)]).unwrap();
        let mut m = ContactMonitor::default();
        for k in 0..3000 {
            let t = k as f64 * 1e-3;
            body_tick(&mut m, &mut map, t, [-0.1 * t, 0.0], [-0.1, 0.0]);
        }
        assert_eq!(contact_counts(&m.contacts), (0, 1), "{:?}", m.contacts);
        assert!(m.contacts[0].robot_approach < 0.0);
    }

    #[test]
    fn a_new_episode_after_the_contact_ends() {
        // A person at rest, the robot steps in, out and in again.
        let mut map = MovingMap::new(&[person(1.0, 0.0)], &[]).unwrap();
        let mut m = ContactMonitor::default();
        for (k, x) in [0.0, 0.6, 0.6, 0.0, 0.6].into_iter().enumerate() {
            body_tick(&mut m, &mut map, k as f64, [x, 0.0], [0.2, 0.0]);
        }
        assert_eq!(m.contacts.len(), 2);
        assert_eq!(m.contacts[1].time, 4.0);
    }

    #[test]
    fn feet_landed_on_a_person_are_the_robots_planted_feet_stepped_on_are_not() {
        let robot = RobotParams::default();
        let far = Vector2::new(-50.0, 0.0);
        // A person 1 m ahead of a planted foot, walking onto it.
        let mut map = MovingMap::new(&[person(1.0, 0.0)], &[Vector2::new(-0.5, 0.0)]).unwrap();
        let mut m = ContactMonitor::default();
        for k in 0..2000 {
            let t = k as f64 * 1e-3;
            map.set_time(t);
            m.observe(
                &map,
                &robot,
                t,
                far,
                Vector2::zeros(),
                Vector2::zeros(),
                0.0,
                k == 0,
            );
        }
        let feet: Vec<_> = m
            .contacts
            .iter()
            .filter(|c| c.part == ContactPart::Foot)
            .collect();
        assert_eq!(feet.len(), 1);
        assert_eq!(feet[0].cause, ContactCause::Obstacle);
        // A foot landing where the person is.
        let mut map = MovingMap::new(&[person(1.0, 0.0)], &[Vector2::new(-0.5, 0.0)]).unwrap();
        let mut m = ContactMonitor::default();
        m.observe(
            &map,
            &robot,
            0.0,
            far,
            Vector2::zeros(),
            Vector2::zeros(),
            0.0,
            true,
        );
        assert!(m.contacts.is_empty());
        map.set_time(0.001);
        m.observe(
            &map,
            &robot,
            0.001,
            far,
            Vector2::zeros(),
            Vector2::new(1.0, 0.0),
            0.0,
            true,
        );
        assert_eq!(contact_counts(&m.contacts), (1, 0), "{:?}", m.contacts);
    }

    /// The person of `a_person_walking_into_a_standing_robot_is_the_persons_contact`
    /// (from 1 m to the right, walking left at 0.5 m/s) with the body at
    /// `com(t)` walking at `walk` for 1.2 s (the person over the body from
    /// about 1.04 s when the body stands), the stance foot far away; then a
    /// foot lands at (`foot_x`, 0) and the monitor's contacts are returned.
    fn landing_after(com: impl Fn(f64) -> [f64; 2], walk: [f64; 2], foot_x: f64) -> Vec<Contact> {
        let robot = RobotParams::default();
        let mut map = MovingMap::new(&[person(1.0, 0.0)], &[Vector2::new(-0.5, 0.0)]).unwrap();
        let mut m = ContactMonitor::default();
        for k in 0..1200 {
            let t = k as f64 * 1e-3;
            body_tick(&mut m, &mut map, t, com(t), walk);
        }
        let t = 1.2;
        map.set_time(t);
        let c = com(t);
        m.observe(
            &map,
            &robot,
            t,
            Vector2::new(c[0], c[1]),
            Vector2::new(walk[0], walk[1]),
            Vector2::new(foot_x, 0.0),
            0.0,
            true,
        );
        m.contacts
    }

    #[test]
    fn a_foot_landing_on_a_person_inside_the_body_takes_the_body_contacts_cause() {
        // The person walked into the standing body (theirs); at 1.2 s they are
        // at x = 0.4, over the body, and the next foot lands under them: theirs.
        let parts = |contacts: &[Contact]| -> Vec<_> {
            contacts.iter().map(|c| (c.part, c.cause)).collect()
        };
        let contacts = landing_after(|_| [0.0, 0.0], [0.0, 0.0], 0.4);
        let expected = [
            (ContactPart::Body, ContactCause::Obstacle),
            (ContactPart::Foot, ContactCause::Obstacle),
        ];
        assert_eq!(parts(&contacts), expected, "{contacts:?}");
        // The robot walked into the person at 0.3 m/s (its contact); the foot
        // landing on them is the robot's too.
        let contacts = landing_after(|t| [0.3 * t, 0.0], [0.3, 0.0], 0.6);
        let expected = [
            (ContactPart::Body, ContactCause::Robot),
            (ContactPart::Foot, ContactCause::Robot),
        ];
        assert_eq!(parts(&contacts), expected, "{contacts:?}");
    }

    #[test]
    fn a_foot_landing_on_a_person_clear_of_the_body_is_the_robots() {
        // The body backs away ahead of the person (at x = -0.6 - 0.3 t, 0.7 m
        // or more from them: no body contact) and the foot lands under the
        // person, who walked onto that spot during the swing: the robot's.
        let contacts = landing_after(|t| [-0.6 - 0.3 * t, 0.0], [-0.3, 0.0], 0.4);
        let parts: Vec<_> = contacts.iter().map(|c| (c.part, c.cause)).collect();
        assert_eq!(
            parts,
            [(ContactPart::Foot, ContactCause::Robot)],
            "{contacts:?}"
        );
    }

    #[test]
    fn mean_velocity_is_the_displacement_over_the_window() {
        let samples: Vec<Sample> = (0..=1000)
            .map(|k| {
                let t = k as f64 * 1e-3;
                Sample {
                    time: t,
                    // A sway of amplitude 0.05 m at 2.5 Hz over a walk at 0.4 m/s.
                    position: Vector2::new(
                        0.4 * t,
                        0.05 * (core::f64::consts::TAU * 2.5 * t).sin(),
                    ),
                    velocity: Vector2::zeros(),
                    heading: 0.0,
                    turning_rate: 0.0,
                    stance_side: ldcbf_controller::Side::Left,
                    clearance: f64::INFINITY,
                }
            })
            .collect();
        let v = mean_velocity(&samples, 400);
        assert!((v - Vector2::new(0.4, 0.0)).norm() < 1e-9, "{v}");
        assert_eq!(mean_velocity(&samples[..1], 400), Vector2::zeros());
    }
}
