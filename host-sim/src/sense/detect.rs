//! What a scanning LiDAR sees in time: the part of a thin tip hidden between
//! two rays, and the sharpest tip the robot meets without contact
//! (docs/safety.md, "Thin tips and the ray spacing").
//!
//! A ray sees only what lies on it. Take a tip of full angle `theta`
//! pointing at the sensor from range `r_tip`, rays `dphi` apart: the ray
//! nearest the tip's axis is at most `phi = dphi / 2` from it and meets the
//! tip's side where the tip is as wide as the gap between the rays there; the
//! part in front of that hit is between two rays, seen free by the rays on
//! either side. Along the axis it is
//!
//! ```text
//! hidden = r_tip tan(phi) / (tan(theta / 2) - tan(phi)),   phi = dphi / 2,
//! ```
//!
//! (unbounded when `theta <= dphi`: the whole tip fits between two rays).
//! The length grows with the range, so no rule on the cells near a hit
//! bounds it: only the ray spacing does. The barrier keeps the CoM at least
//! the margin `M` (`Config::barrier_margin`) from what is seen, i.e. from
//! the hit, at range `rho = r_tip tan(theta/2) / (tan(theta/2) cos(phi) -
//! sin(phi))`; the body (radius `R`) stays off the tip when `r_tip >= R` at
//! `rho = M`:
//!
//! ```text
//! tan(theta / 2) >= sin(phi) / (cos(phi) - R / M).
//! ```
//!
//! The default humanoid (`R = 0.25 m`, `M = 0.351 m` at delta = 0.05,
//! `0.291 m` at delta = 0): 1 degree between rays needs tips of at least
//! 3.5 degrees (7.2 at delta = 0); 0.25 degree (1440 rays) at least 0.87
//! degree (1.8 at delta = 0).

use crate::world::Polygon;

/// Length (m) of the part of a tip hidden between two rays, along its axis:
/// full tip angle `theta` (rad), pointing at the sensor from range `r_tip`
/// (m), rays `dphi` (rad) apart, the worst bearing (module docs). Infinite
/// when `theta <= dphi`.
pub fn hidden_tip_length(r_tip: f64, theta: f64, dphi: f64) -> f64 {
    let (a, b) = ((0.5 * theta).tan(), (0.5 * dphi).tan());
    if a <= b {
        f64::INFINITY
    } else {
        r_tip * b / (a - b)
    }
}

/// The smallest full tip angle (rad) a robot of body radius `body_radius`
/// (m) with barrier margin `margin` (m, `> body_radius`) meets without
/// contact when the rays are `dphi` (rad) apart (module docs); `pi` when
/// the margin leaves no room (`margin <= body_radius / cos(dphi / 2)`).
pub fn smallest_safe_tip_angle(dphi: f64, body_radius: f64, margin: f64) -> f64 {
    let phi = 0.5 * dphi;
    let den = phi.cos() - body_radius / margin;
    if den <= 0.0 {
        core::f64::consts::PI
    } else {
        2.0 * (phi.sin() / den).atan()
    }
}

/// A corner of an obstacle sharper than the LiDAR meets in time
/// ([`smallest_safe_tip_angle`]): pointed at the robot, the part of it hidden
/// between two rays can reach the body before it is seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SharpCorner {
    /// Index of the obstacle (in the scenario's `obstacles`).
    pub obstacle: usize,
    /// The corner's interior angle, rad.
    pub angle: f64,
    /// The smallest tip angle met without contact, rad.
    pub limit: f64,
}

/// The obstacles (any frame) with a corner sharper than a LiDAR of `rays`
/// rays over 360 degrees meets in time, for body radius `body_radius` (m) and
/// barrier margin `margin` (m): their sharpest corner each, in obstacle order.
pub fn sharp_corners(
    obstacles: &[Polygon],
    rays: u32,
    body_radius: f64,
    margin: f64,
) -> Vec<SharpCorner> {
    let dphi = core::f64::consts::TAU / f64::from(rays.max(1));
    let limit = smallest_safe_tip_angle(dphi, body_radius, margin);
    obstacles
        .iter()
        .enumerate()
        .filter_map(|(obstacle, p)| {
            let v = p.vertices();
            let n = v.len();
            let angle = (0..n)
                .map(|i| {
                    let (a, b) = (v[(i + n - 1) % n] - v[i], v[(i + 1) % n] - v[i]);
                    (a.x * b.y - a.y * b.x).abs().atan2(a.dot(&b))
                })
                .fold(f64::INFINITY, f64::min);
            (angle < limit).then_some(SharpCorner {
                obstacle,
                angle,
                limit,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sense::{Lidar, LidarParams};
    use ldcbf_controller::nalgebra::Vector2;

    /// A tip of full angle `theta` and length `len` (m) at range `r_tip`
    /// from the origin, its axis along `axis` (rad), pointing at the origin.
    fn tip(r_tip: f64, theta: f64, len: f64, axis: f64) -> Polygon {
        let u = Vector2::new(axis.cos(), axis.sin());
        let w = Vector2::new(-u.y, u.x);
        let t = u * r_tip;
        let half = len * (0.5 * theta).tan();
        let (b1, b2) = (t + u * len + w * half, t + u * len - w * half);
        Polygon::new(&[[t.x, t.y], [b2.x, b2.y], [b1.x, b1.y]]).unwrap()
    }

    /// The simulated LiDAR (noise-free) hides no more of a tip than the
    /// bound, and the bound is reached (within 5 %) at the worst bearing.
    #[test]
    fn a_tip_is_hidden_between_two_rays_no_longer_than_the_bound() {
        for (rays, theta_deg, r_tip) in [(360u32, 2.08f64, 0.8), (360, 5.0, 1.5), (1440, 2.08, 0.4)]
        {
            let params = LidarParams {
                rays,
                noise_sigma: 0.0,
                ..LidarParams::default()
            };
            let mut lidar = Lidar::new(params, 1).unwrap();
            let dphi = core::f64::consts::TAU / f64::from(rays);
            let theta = theta_deg.to_radians();
            let bound = hidden_tip_length(r_tip, theta, dphi);
            let mut worst: f64 = 0.0;
            // Axis bearings across one ray spacing.
            for k in 0..40 {
                let axis = dphi * f64::from(k) / 40.0;
                let poly = tip(r_tip, theta, 1.0, axis);
                let u = Vector2::new(axis.cos(), axis.sin());
                let rays = lidar.scan_rays(Vector2::zeros(), 0.0, std::slice::from_ref(&poly));
                let nearest = rays
                    .iter()
                    .flatten()
                    .map(|p| u.dot(p))
                    .fold(f64::INFINITY, f64::min);
                let hidden = nearest - r_tip;
                assert!(
                    hidden <= bound + 1e-9,
                    "{rays:?} rays, {theta_deg} deg: hidden {hidden} > {bound}"
                );
                worst = worst.max(hidden);
            }
            assert!(worst >= 0.95 * bound, "{worst} vs {bound}");
        }
        assert_eq!(hidden_tip_length(1.0, 0.01, 0.02), f64::INFINITY);
    }

    /// `crowded` seed 174's needle (2.08 degrees) is sharper than the
    /// default humanoid meets safely with 1 degree between rays, at either
    /// delta, and within what 0.25 degree allows at both.
    #[test]
    fn the_crowded_174_needle_needs_a_quarter_degree() {
        let needle = 2.08f64.to_radians();
        for delta in [0.0, 0.05] {
            let config =
                crate::world::robot::RobotParams::default().apply(ldcbf_controller::Config {
                    delta,
                    ..ldcbf_controller::Config::default()
                });
            let (r, m) = (config.body_radius, config.barrier_margin());
            let coarse = smallest_safe_tip_angle(1f64.to_radians(), r, m);
            let fine = smallest_safe_tip_angle(0.25f64.to_radians(), r, m);
            assert!(
                coarse > needle && needle > fine,
                "delta {delta}: {coarse} {fine}"
            );
            // At exactly the smallest safe angle, the tip's range when the
            // hit is at the margin is the body radius.
            let phi = 0.125f64.to_radians();
            let a = (0.5 * fine).tan();
            let r_tip = m * (a * phi.cos() - phi.sin()) / a;
            assert!((r_tip - r).abs() < 1e-12, "{r_tip}");
        }
        assert_eq!(
            smallest_safe_tip_angle(0.1, 0.3, 0.3),
            core::f64::consts::PI
        );
    }

    /// A sliver of 2 degrees is flagged for 360 rays (its sharpest corner,
    /// not its two wide ones), not for 1440; a square never.
    #[test]
    fn a_sliver_sharper_than_the_ray_spacing_allows_is_named() {
        let sliver = tip(2.0, 2f64.to_radians(), 0.7, 0.3);
        let square = Polygon::new(&[[3.0, 0.0], [3.5, 0.0], [3.5, 0.5], [3.0, 0.5]]).unwrap();
        let obstacles = [square, sliver];
        let found = sharp_corners(&obstacles, 360, 0.25, 0.351);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].obstacle, 1);
        assert!(
            (found[0].angle - 2f64.to_radians()).abs() < 1e-9,
            "{found:?}"
        );
        assert!(found[0].limit > found[0].angle);
        assert!(sharp_corners(&obstacles, 1440, 0.25, 0.351).is_empty());
    }
}
