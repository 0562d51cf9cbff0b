//! CrowdNav's ORCA baseline: the robot is a holonomic disk of our body's
//! radius whose velocity is the ORCA velocity of `dodgy_2d`
//! ([`crate::world::crowd::orca::velocity`]) toward the goal at
//! [`NOMINAL_SPEED`], seeing every human with its current velocity; the
//! humans see it (as an ORCA agent that takes half of each avoidance) only
//! with a visible robot. Robot and humans choose velocities at the same
//! instants, every [`DECISION_PERIOD`]; positions move every [`DT`].
//!
//! A collision (a human within the sum of the radii) counts once per
//! episode, as the robot's when it was moving toward the human at more than
//! [`STANDING_SPEED`] or the human stood (the rule of
//! [`crate::sim::ContactCause`] for a body without sway).

use ldcbf_controller::nalgebra::Vector2;

use super::{CaseRow, CrowdNavRequest, time_limit, unit};
use crate::sim::STANDING_SPEED;
use crate::world::crowd::families::crowdnav_case;
use crate::world::crowd::{Body, Crowd, DECISION_PERIOD, RobotBody, orca};
use crate::world::people::NOMINAL_SPEED;
use crate::world::robot::RobotParams;

/// The position step of the ORCA robot's loop, s.
pub const DT: f64 = 0.01;

/// CrowdNav's goal radius (its robot's radius), m.
pub const GOAL_RADIUS: f64 = 0.3;

/// Runs case `seed` of `req` with the ORCA robot.
pub fn case(req: &CrowdNavRequest, seed: u64) -> CaseRow {
    let radius = RobotParams::default().body_radius;
    let c = crowdnav_case(req.layout, req.humans, seed, radius);
    let goal = c.layout.goal;
    let mut people = c.people;
    for p in &mut people {
        p.sees_robot = req.robot_visible;
    }
    let radii: Vec<f64> = people.iter().map(|p| p.radius).collect();
    let mut crowd = Crowd::new(people, &[]);
    let (mut p, mut v) = (c.layout.start, Vector2::zeros());
    let ticks = (time_limit() / DT).round() as usize;
    let per_decision = (DECISION_PERIOD / DT).round() as usize;
    let mut touching = vec![false; radii.len()];
    let (mut collision, mut robot_collision) = (false, false);
    let mut seps = Vec::with_capacity(ticks);
    let mut reached = None;
    for k in 0..ticks {
        if k % per_decision == 0 {
            let others: Vec<Body> = crowd
                .positions()
                .iter()
                .zip(crowd.velocities())
                .zip(&radii)
                .map(|((&position, &velocity), &radius)| Body {
                    position,
                    velocity,
                    radius,
                })
                .collect();
            let me = Body {
                position: p,
                velocity: v,
                radius,
            };
            let to_goal = goal - p;
            let preferred = to_goal * (NOMINAL_SPEED / to_goal.norm().max(NOMINAL_SPEED));
            v = orca::velocity(&me, preferred, NOMINAL_SPEED, &others, &[], DECISION_PERIOD);
        }
        let body = RobotBody {
            position: p,
            velocity: v,
            radius,
        };
        crowd.step(DT, Some(&body));
        p += v * DT;
        let mut sep = f64::INFINITY;
        for (i, (h, hv)) in crowd.positions().iter().zip(crowd.velocities()).enumerate() {
            let d = (h - p).norm() - radii[i] - radius;
            sep = sep.min(d);
            let now = d < 0.0;
            if now && !touching[i] {
                collision = true;
                let approach = v.dot(&unit(h - p));
                robot_collision |= *hv == Vector2::zeros() || approach > STANDING_SPEED;
            }
            touching[i] = now;
        }
        seps.push(sep);
        if (p - goal).norm() <= GOAL_RADIUS {
            reached = Some((k + 1) as f64 * DT);
            break;
        }
    }
    CaseRow::new(seed, reached, (collision, robot_collision), &seps, DT)
}
