//! ORCA people and the ORCA robot of the crowd-navigation benchmark: one
//! velocity choice through the crate `dodgy_2d` (a port of RVO2; the ORCA
//! itself is the crate's, not ours).
//!
//! The settings are those of CrowdNav's ORCA policy (Chen et al. 2019,
//! `crowd_nav/policy/orca.py`, after RVO2): neighbours within
//! [`NEIGHBOUR_DIST`] (10 m), at most [`MAX_NEIGHBOURS`] (10) of the nearest,
//! time horizon [`TIME_HORIZON`] (5 s) for agents and for obstacles, the
//! agent's radius plus 0.01 m, the maximum speed the preferred speed, equal
//! responsibility for every agent (each takes half of a pairwise
//! avoidance), the preferred velocity turned by 0.01 rad ([`perturbed`]).
//! A wall is a closed `dodgy_2d` obstacle (its vertices
//! counter-clockwise: solid inside), kept at the agent's radius.

use std::borrow::Cow;

use dodgy_2d::{Agent, AvoidanceOptions, Obstacle, Vec2};
use ldcbf_controller::nalgebra::Vector2;

use super::Body;
use crate::world::Polygon;

/// Agents farther than this are not avoided, m.
pub const NEIGHBOUR_DIST: f64 = 10.0;
/// At most this many of the nearest agents are avoided.
pub const MAX_NEIGHBOURS: usize = 10;
/// ORCA's time horizon for agents and for obstacles, s.
pub const TIME_HORIZON: f64 = 5.0;
/// Added to every agent's radius, m (CrowdNav's `radius + 0.01`).
pub const RADIUS_PAD: f64 = 0.01;

/// The angle every ORCA person's preferred velocity is turned by, rad.
pub const PERTURBATION: f64 = 0.01;

/// `preferred` turned counter-clockwise by [`PERTURBATION`]. Two ORCA
/// agents walking exactly head-on choose exactly opposite velocities and
/// stop face to face for ever (a symmetric deadlock; RVO2's own examples
/// perturb the preferred velocities at random for this); the fixed turn
/// breaks the symmetry deterministically (both keep to the same side).
pub fn perturbed(preferred: Vector2<f64>) -> Vector2<f64> {
    let (s, c) = PERTURBATION.sin_cos();
    Vector2::new(
        c * preferred.x - s * preferred.y,
        s * preferred.x + c * preferred.y,
    )
}

fn v2(p: Vector2<f64>) -> Vec2 {
    Vec2::new(p.x as f32, p.y as f32)
}

fn agent(b: &Body) -> Agent {
    Agent {
        position: v2(b.position),
        velocity: v2(b.velocity),
        radius: (b.radius + RADIUS_PAD) as f32,
        avoidance_responsibility: 1.0,
    }
}

/// A wall as a closed `dodgy_2d` obstacle (vertices counter-clockwise).
pub fn obstacle(poly: &Polygon) -> Obstacle {
    let mut vertices: Vec<Vec2> = poly.vertices().iter().map(|p| v2(*p)).collect();
    let n = vertices.len();
    let area2: f32 = (0..n)
        .map(|i| {
            let (a, b) = (vertices[i], vertices[(i + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum();
    if area2 < 0.0 {
        vertices.reverse();
    }
    Obstacle::Closed { vertices }
}

/// The ORCA velocity of `me` (m/s): the velocity nearest to `preferred`
/// of speed at most `max_speed` that avoids the nearest `others` (each
/// assumed to take half of the avoidance, with its current velocity) for
/// [`TIME_HORIZON`] and `walls` for as long; `dt` (s) is the time step in
/// which an existing overlap is to be resolved.
pub fn velocity(
    me: &Body,
    preferred: Vector2<f64>,
    max_speed: f64,
    others: &[Body],
    walls: &[Obstacle],
    dt: f64,
) -> Vector2<f64> {
    let mut near: Vec<(f64, &Body)> = others
        .iter()
        .map(|o| ((o.position - me.position).norm(), o))
        .filter(|(d, _)| *d <= NEIGHBOUR_DIST)
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    near.truncate(MAX_NEIGHBOURS);
    let neighbours: Vec<Cow<'_, Agent>> = near.iter().map(|(_, b)| Cow::Owned(agent(b))).collect();
    let walls: Vec<Cow<'_, Obstacle>> = walls.iter().map(Cow::Borrowed).collect();
    let v = agent(me).compute_avoiding_velocity(
        &neighbours,
        &walls,
        v2(preferred),
        max_speed as f32,
        dt as f32,
        &AvoidanceOptions {
            obstacle_margin: (me.radius + RADIUS_PAD) as f32,
            time_horizon: TIME_HORIZON as f32,
            obstacle_time_horizon: TIME_HORIZON as f32,
        },
    );
    let v = Vector2::new(f64::from(v.x), f64::from(v.y));
    if v.x.is_finite() && v.y.is_finite() {
        super::clip(v, max_speed)
    } else {
        Vector2::zeros()
    }
}
