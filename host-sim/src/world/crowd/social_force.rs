//! The social force model of D. Helbing and P. Molnar, "Social force model
//! for pedestrian dynamics", Phys. Rev. E 51, 4282 (1995), with the
//! parameters of that paper:
//!
//! `dv/dt = (v0 e - v) / tau + sum_b w(e, f_ab) f_ab + sum_B w(e, f_aB) f_aB`,
//!
//! * the driving term toward the preferred velocity `v0 e`, relaxation time
//!   [`TAU`] = 0.5 s;
//! * the repulsion of another pedestrian `b`, `f_ab = -grad_r V(b)` with
//!   `V(b) = V0 exp(-b / sigma)`, [`V0`] = 2.1 m^2/s^2, [`SIGMA`] = 0.3 m,
//!   and `b` the semi-minor axis of the ellipse through `a` with foci at
//!   `b`'s position and its position a step [`STEP_TIME`] = 2 s ahead:
//!   `2b = sqrt((|r| + |r - v_b dt|)^2 - (|v_b| dt)^2)`, `r = r_a - r_b`;
//!   the visible robot is such a pedestrian, with its current velocity;
//! * the repulsion of a wall `B`, `f_aB = -grad U(|r_aB|)` with
//!   `U = U0 exp(-|r_aB| / R)`, [`U0`] = 10 m^2/s^2, [`R`] = 0.2 m, `r_aB`
//!   from the wall's nearest point to `a`;
//! * the field of view: a force from behind (outside the angle `2 phi` =
//!   200 degrees around the walking direction `e`) counts [`C_BEHIND`] =
//!   0.5 of its strength;
//! * the speed is capped at [`MAX_SPEED_FACTOR`] = 1.3 times the preferred
//!   speed.
//!
//! In the paper pedestrians are points; our people have bodies, so the
//! potentials are taken in the distances between body surfaces (the centre
//! distance less both radii, and the wall distance less the radius), as the
//! later form of the model does (Helbing, Farkas & Vicsek, Nature 407, 487,
//! 2000: `r_ab - d_ab`). The velocity is integrated by explicit Euler over
//! the people's decision period.

use ldcbf_controller::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;

use super::{Body, clip};
use crate::world::Polygon;

/// Relaxation time toward the preferred velocity, s.
pub const TAU: f64 = 0.5;
/// Strength of the pedestrian potential, m^2/s^2.
pub const V0: f64 = 2.1;
/// Range of the pedestrian potential, m.
pub const SIGMA: f64 = 0.3;
/// The step time of the ellipse of the pedestrian potential, s.
pub const STEP_TIME: f64 = 2.0;
/// Strength of the wall potential, m^2/s^2.
pub const U0: f64 = 10.0;
/// Range of the wall potential, m.
pub const R: f64 = 0.2;
/// Half the angle of the field of view, rad (2 phi = 200 degrees).
pub const PHI: f64 = 100.0 * core::f64::consts::PI / 180.0;
/// Weight of a force from outside the field of view.
pub const C_BEHIND: f64 = 0.5;
/// Largest speed, as a multiple of the preferred speed.
pub const MAX_SPEED_FACTOR: f64 = 1.3;

/// The semi-minor axis `b` of the ellipse (module docs) for `r = r_a - r_b`
/// and `step = v_b dt`, m.
fn semi_minor(r: Vector2<f64>, step: Vector2<f64>) -> f64 {
    let s = r.norm() + (r - step).norm();
    0.5 * (s * s - step.norm_squared()).max(0.0).sqrt()
}

/// The repulsion of a pedestrian at `r = r_a - r_b` walking at `v_b`, m/s^2
/// (minus the gradient of `V(b)`, by central differences of `b`), the two
/// bodies' radii summing to `radii` (m): `r` is first shortened by `radii`
/// (to at least 1 mm).
pub fn pedestrian_force(r: Vector2<f64>, v_b: Vector2<f64>, radii: f64) -> Vector2<f64> {
    let n = r.norm();
    let r = if n > 1e-9 {
        r * ((n - radii).max(1e-3) / n)
    } else {
        Vector2::new(1e-3, 0.0)
    };
    let step = v_b * STEP_TIME;
    let h = 1e-6;
    let grad = Vector2::new(
        semi_minor(r + Vector2::x() * h, step) - semi_minor(r - Vector2::x() * h, step),
        semi_minor(r + Vector2::y() * h, step) - semi_minor(r - Vector2::y() * h, step),
    ) / (2.0 * h);
    grad * (V0 / SIGMA * (-semi_minor(r, step) / SIGMA).exp())
}

/// The repulsion of a wall whose nearest point is at `r_aB` from `a`, m/s^2.
pub fn wall_force(r_ab: Vector2<f64>) -> Vector2<f64> {
    let d = r_ab.norm();
    if d < 1e-9 {
        return Vector2::zeros();
    }
    r_ab / d * (U0 / R * (-d / R).exp())
}

/// The weight of a force `f` on a pedestrian walking along `e` (unit).
fn weight(e: Vector2<f64>, f: Vector2<f64>) -> f64 {
    if e.dot(&f) >= f.norm() * PHI.cos() {
        1.0
    } else {
        C_BEHIND
    }
}

/// The velocity of `me` after `dt` (s) of the model (m/s), with preferred
/// velocity `preferred`, preferred speed `speed`, among `others` and `walls`.
pub fn velocity(
    me: &Body,
    preferred: Vector2<f64>,
    speed: f64,
    others: &[Body],
    walls: &[Polygon],
    dt: f64,
) -> Vector2<f64> {
    let e = if preferred.norm() > 1e-9 {
        preferred / preferred.norm()
    } else if me.velocity.norm() > 1e-9 {
        me.velocity / me.velocity.norm()
    } else {
        Vector2::zeros()
    };
    let mut a = (preferred - me.velocity) / TAU;
    for o in others {
        let f = pedestrian_force(me.position - o.position, o.velocity, me.radius + o.radius);
        a += f * weight(e, f);
    }
    for w in walls {
        let c = closest_point_point_polygon(&me.position, w);
        let mut r_ab = me.position - c.point;
        if c.signed_distance < 0.0 {
            // Inside a wall: pushed out through the nearest side.
            r_ab = -r_ab;
        }
        let d = r_ab.norm();
        let r_ab = if d > 1e-9 {
            r_ab * ((d - me.radius).max(1e-3) / d)
        } else {
            r_ab
        };
        let f = wall_force(r_ab);
        a += f * weight(e, f);
    }
    let v = clip(me.velocity + a * dt, MAX_SPEED_FACTOR * speed);
    if v.x.is_finite() && v.y.is_finite() {
        v
    } else {
        Vector2::zeros()
    }
}
