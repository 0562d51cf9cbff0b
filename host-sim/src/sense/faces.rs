//! How far each ray of a scan is seen free, from the face its neighbours fit.
//!
//! A single hit is its surface's position give or take the noise (Gaussian,
//! `noise_sigma` per axis), so one ray alone may count as seen free only up
//! to `3 noise_sigma + free_margin` short of its hit
//! ([`super::free_tolerance`]). With 2.5 cm cells and 1 cm noise that leaves
//! the cells of the last 3.5 cm in front of a wall never cleared, and a noise
//! hit that lands in one of them (a few in a thousand rays land 3 sigma or
//! more in front) marks it for good: a *ghost cell* one or two cells in front
//! of the wall, which narrows a corridor by up to 6 cm a side.
//!
//! The rays of a straight face measure the same line: the total-least-squares
//! line of the `2 HALF_WINDOW + 1` consecutive hits centred on a ray locates
//! the face along its normal with the standard deviation of a regression
//! line's prediction, `sigma_fit = noise_sigma sqrt(1/N + a^2 / S)` (`a` the
//! ray's point along the line from the hits' centroid, `S` the sum of the
//! hits' squared positions along it), about `noise_sigma / sqrt(7)` for the
//! centre ray. The ray then counts as seen free up to the fitted line less
//! `3 sigma_fit + free_margin` along the normal (divided by the cosine of its
//! incidence along the ray): the same three-sigma rule, applied to the fit
//! instead of the single hit. The fit is used only when every hit of the
//! window has a hit and lies within `3 noise_sigma` of the line (one face to
//! the noise level: a corner, a gap or a thin object in front of the face
//! shows as a larger residual and the ray keeps the single-hit rule), and
//! never makes a ray's free part shorter than the single-hit rule does.
//!
//! Marking is unchanged: every hit still marks its cell and wins over the
//! misses of its own scan, so a thin obstacle hit in every scan stays
//! occupied; what the fit adds is the evidence of later scans against a noise
//! hit (this is the range-noise term of the inverse sensor model: S. Thrun,
//! W. Burgard, D. Fox, *Probabilistic Robotics*, MIT Press 2005, 9.2, where a
//! cell well in front of a measured range is free).

use ldcbf_controller::nalgebra::Vector2;

use super::{LidarParams, free_tolerance, ray_direction};

/// Hits on each side of a ray in its face's fit (7 hits per fit).
pub const HALF_WINDOW: usize = 3;

/// Smallest `|cos|` of the angle between a ray and its fitted face's normal
/// for which the fit is used (grazing rays keep the single-hit rule).
const MIN_INCIDENCE_COS: f64 = 0.2;

/// The free length of every ray of a scan, m: `rays[k]` is ray `k`'s hit
/// point (world frame, m) or `None` (as [`super::Lidar::scan_rays`] returns
/// them) from `origin` (m) with the sensor's zero angle along `heading`
/// (rad); the free length is along the ray's direction. For a hit ray, the
/// larger of the single-hit rule (`|p - origin| - free_tolerance`) and the
/// fitted face's (module docs), never more than `|p - origin|`; for a missed
/// ray, `params.range`.
pub fn free_lengths(
    rays: &[Option<Vector2<f64>>],
    origin: Vector2<f64>,
    heading: f64,
    params: &LidarParams,
) -> Vec<f64> {
    fit_scan(rays, origin, heading, params).1
}

/// [`free_lengths`] and the point each ray marks occupied (world frame, m):
/// where the ray's face fit is used, the ray's point on the fitted face
/// (module docs), else its hit point; `None` for a missed ray.
pub fn fit_scan(
    rays: &[Option<Vector2<f64>>],
    origin: Vector2<f64>,
    heading: f64,
    params: &LidarParams,
) -> (Vec<Option<Vector2<f64>>>, Vec<f64>) {
    let n = rays.len();
    let tol = free_tolerance(params);
    let sigma = params.noise_sigma;
    let mut marks = Vec::with_capacity(n);
    let mut out = Vec::with_capacity(n);
    let mut window: Vec<Vector2<f64>> = Vec::with_capacity(2 * HALF_WINDOW + 1);
    for (k, ray) in rays.iter().enumerate() {
        let Some(p) = ray else {
            marks.push(None);
            out.push(params.range);
            continue;
        };
        let r = (p - origin).norm();
        let single = r - tol;
        window.clear();
        if n > 2 * HALF_WINDOW {
            for o in 0..=2 * HALF_WINDOW {
                if let Some(q) = rays[(k + n + o - HALF_WINDOW) % n] {
                    window.push(q);
                }
            }
        }
        let d = ray_direction(heading, k, n);
        let fitted = if window.len() == 2 * HALF_WINDOW + 1 {
            fitted_free_length(&window, origin, d, sigma, params.free_margin)
        } else {
            None
        };
        match fitted {
            Some((t, free)) => {
                marks.push(Some(origin + d * t));
                out.push(free.min(r).max(single));
            }
            None => {
                marks.push(Some(*p));
                out.push(single);
            }
        }
    }
    (marks, out)
}

/// The distance along the ray from `origin` along the unit `d` to the face
/// fitted to `pts` and the ray's fitted free length (m, module docs), or
/// `None` when the window is not one face to the noise level or the ray
/// grazes it.
fn fitted_free_length(
    pts: &[Vector2<f64>],
    origin: Vector2<f64>,
    d: Vector2<f64>,
    sigma: f64,
    margin: f64,
) -> Option<(f64, f64)> {
    let m = pts.len() as f64;
    let c = pts.iter().fold(Vector2::zeros(), |s, p| s + p) / m;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let e = p - c;
        sxx += e.x * e.x;
        sxy += e.x * e.y;
        syy += e.y * e.y;
    }
    let th = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let u = Vector2::new(th.cos(), th.sin());
    // Normal facing the sensor.
    let mut nrm = Vector2::new(-u.y, u.x);
    if nrm.dot(&(origin - c)) < 0.0 {
        nrm = -nrm;
    }
    let mut s = 0.0;
    for p in pts {
        let e = p - c;
        if nrm.dot(&e).abs() > 3.0 * sigma {
            return None;
        }
        s += u.dot(&e).powi(2);
    }
    let cos = -nrm.dot(&d);
    if cos < MIN_INCIDENCE_COS || s <= 0.0 {
        return None;
    }
    // Distance along the ray to the fitted line, and the ray's point on it.
    let t = nrm.dot(&(origin - c)) / cos;
    let a = u.dot(&(origin + d * t - c));
    let sigma_fit = sigma * (1.0 / m + a * a / s).sqrt();
    Some((t, t - (3.0 * sigma_fit + margin) / cos))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sense::Lidar;
    use crate::world::Polygon;

    fn wall() -> Vec<Polygon> {
        // A wall whose face is the line x = 1.5 (m), 4 m long.
        vec![Polygon::new(&[[1.5, -2.0], [1.7, -2.0], [1.7, 2.0], [1.5, 2.0]]).unwrap()]
    }

    #[test]
    fn a_wall_faced_head_on_is_seen_free_closer_to_its_face() {
        let params = LidarParams::default();
        let mut lidar = Lidar::new(params.clone(), 3).unwrap();
        let o = Vector2::new(0.0, 0.0);
        let tol = free_tolerance(&params);
        let mut fitted_closer = 0;
        for _ in 0..20 {
            let rays = lidar.scan_rays(o, 0.0, &wall());
            let free = free_lengths(&rays, o, 0.0, &params);
            for (k, (ray, f)) in rays.iter().zip(&free).enumerate() {
                let d = ray_direction(0.0, k, rays.len());
                match ray {
                    None => assert_eq!(*f, params.range),
                    Some(p) => {
                        let r = (p - o).norm();
                        assert!(*f >= r - tol - 1e-12 && *f <= r + 1e-12, "ray {k}");
                        // A fitted length never reaches the true face (x =
                        // 1.5); the single-hit rule is three-sigma.
                        let end = o + d * *f;
                        if *f > r - tol {
                            assert!(end.x < 1.5, "ray {k}: {end:?}");
                        }
                        if d.x > 0.9 && *f > r - tol + 0.005 {
                            fitted_closer += 1;
                        }
                    }
                }
            }
        }
        // Most head-on rays (about 51 a scan) clear more than 5 mm closer to
        // the face.
        assert!(fitted_closer > 20 * 35, "{fitted_closer}");
    }

    /// Ten scans of a wall (face at `x_w`, at five offsets within a cell)
    /// and an 8 cm post in front of it, through [`fit_scan`] and
    /// [`OccupancyMap::update_scan`]: the map's nearest occupied cell in
    /// front of the wall starts at most a cell and 1.5 cm (the fit's 3.5
    /// sigma) before the face, a noise hit 4 sigma in front of the face
    /// (injected in the first scan) is cleared, and the post stays occupied.
    #[test]
    fn the_map_sees_a_wall_at_most_a_cell_in_front_and_keeps_a_post() {
        use crate::sense::{CellState, MapParams, OccupancyMap};
        let params = LidarParams::default();
        let mut lidar = Lidar::new(params.clone(), 11).unwrap();
        for x_w in [1.001, 1.006, 1.0125, 1.017, 1.024] {
            let mut m = OccupancyMap::new(
                MapParams {
                    padding: 0.0,
                    ..MapParams::default()
                },
                Vector2::new(-2.0, -2.0),
                Vector2::new(2.0, 2.0),
            )
            .unwrap();
            let obstacles = vec![
                Polygon::new(&[[x_w, -2.0], [1.2, -2.0], [1.2, 2.0], [x_w, 2.0]]).unwrap(),
                crate::world::square([0.7, 0.6], 0.04),
            ];
            let o = Vector2::new(0.0, 0.0);
            let ghost = Vector2::new(x_w - 0.04, 0.0);
            for scan in 0..10 {
                let mut rays = lidar.scan_rays(o, 0.0, &obstacles);
                if scan == 0 {
                    rays[0] = Some(ghost);
                }
                let (marks, free) = fit_scan(&rays, o, 0.0, &params);
                m.update_scan(o, 0.0, &marks, &free, 0.1, &[]);
            }
            assert_eq!(m.state_at(ghost), CellState::Free, "x_w {x_w}: ghost");
            let r = m.resolution;
            let face = (0..m.height)
                .flat_map(|j| (0..m.width).map(move |i| (i, j)))
                .filter(|&(i, j)| m.state(i, j) == CellState::Occupied)
                .map(|(i, j)| m.centre(i, j))
                .filter(|c| c.y.abs() < 0.4)
                .map(|c| c.x - 0.5 * r)
                .fold(f64::INFINITY, f64::min);
            assert!(face >= x_w - r - 0.015, "x_w {x_w}: face seen at {face}");
            let post_seen = (0..m.height)
                .flat_map(|j| (0..m.width).map(move |i| (i, j)))
                .filter(|&(i, j)| m.state(i, j) == CellState::Occupied)
                .any(|(i, j)| {
                    ldcbf_controller::closest_point_point_polygon(&m.centre(i, j), &obstacles[1])
                        .signed_distance
                        .abs()
                        < 0.03
                });
            assert!(post_seen, "x_w {x_w}: the post's near face");
        }
    }

    #[test]
    fn a_hit_in_front_of_a_face_keeps_the_single_hit_rule_around_it() {
        let params = LidarParams::default();
        let o = Vector2::new(0.0, 0.0);
        let n = 360;
        // Exact hits on x = 1.5 for the rays within 30 degrees, and ray 0's
        // 5 cm in front (a thin object, or a 5-sigma noise hit).
        let mut rays: Vec<Option<Vector2<f64>>> = (0..n)
            .map(|k| {
                let d = ray_direction(0.0, k, n);
                (d.x > 0.87).then(|| o + d * (1.5 / d.x))
            })
            .collect();
        rays[0] = Some(Vector2::new(1.45, 0.0));
        let free = free_lengths(&rays, o, 0.0, &params);
        let tol = free_tolerance(&params);
        // Its residual shows in the fits of the rays within two of it; at
        // the window's edge (three off) it pulls the fit towards the sensor.
        for k in [n - 2, n - 1, 0, 1, 2] {
            let r = (rays[k].unwrap() - o).norm();
            assert!((free[k] - (r - tol)).abs() < 1e-12, "ray {k}");
        }
        for k in [n - 3, 3] {
            let d = ray_direction(0.0, k, n);
            assert!((o + d * free[k]).x < 1.5 - 0.005, "ray {k}");
        }
        // Rays whose window holds only the face use the fit.
        let r = (rays[10].unwrap() - o).norm();
        assert!(free[10] > r - tol + 0.01, "{} {}", free[10], r - tol);
    }
}
