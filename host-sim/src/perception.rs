//! Perception for unknown maps (SPEC 6, report 5.2): a simulated 2D LiDAR, DBSCAN
//! clustering of its hit points, and one convex obstacle per cluster.
//!
//! World frame W, metres, radians.
//!
//! * [`Lidar::scan`]: `rays` rays from the sensor (at the CoM), ray `i` at angle
//!   `heading + 2 pi i / rays`, cast against the TRUE polygons (nearest edge
//!   crossing). A ray that hits within `range` returns its hit point plus
//!   zero-mean Gaussian noise of standard deviation `noise_sigma` on each axis
//!   (a ChaCha8 generator seeded from the scenario seed: the same run gives the
//!   same scans); a ray that hits nothing within `range` returns nothing.
//! * [`dbscan`]: density-based clustering with radius `eps` (neighbours at
//!   distance `<= eps`) and `min_points` (a point is a core point when at least
//!   `min_points` points, itself included, are within `eps`). Border points join
//!   the first cluster that reaches them; noise points (in no cluster) are
//!   dropped. O(n^2), fine for a few hundred points per scan.
//! * [`cluster_polygon`]: the convex hull of a cluster (Andrew's monotone chain).
//!   A cluster whose hull is degenerate (1 or 2 distinct points, collinear
//!   points) or thinner than `min_thickness` becomes the rectangle aligned with
//!   the cluster's longest chord that contains every point with at least
//!   `min_thickness / 2` to spare across it (and along it): a valid thin
//!   obstacle. A hull with more than `max_vertices` vertices is simplified
//!   conservatively (edge collapse: two neighbouring edges are extended to meet,
//!   smallest added area first), so the polygon still contains every point.
//! * [`visible_polygons`]: a cluster whose polygon comes nearer to the sensor
//!   than the nearest point seen (it joins two obstacles across free space) is
//!   split at its widest seam, recursively, before it reaches the controller.
//!
//! The controller then sees only these inferred polygons; the simulator still
//! measures clearance against the true ones.

use ldcbf_controller::geometry::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::scenario::{MAX_VERTICES, Polygon};

/// LiDAR and clustering settings: the scenario's `[lidar]` table.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LidarParams {
    /// Rays per scan, evenly spread over 360 degrees.
    pub rays: u32,
    /// Maximum range, m.
    pub range: f64,
    /// Standard deviation of the Gaussian noise on each axis of a hit point, m.
    pub noise_sigma: f64,
    /// DBSCAN neighbourhood radius, m.
    pub eps: f64,
    /// DBSCAN core-point threshold (neighbours within `eps`, itself included).
    pub min_points: usize,
    /// Minimum thickness of an inferred obstacle, m (thin and degenerate
    /// clusters become rectangles at least this thick).
    pub min_thickness: f64,
    /// Largest vertex count of an inferred polygon (at most 32).
    pub max_vertices: usize,
}

impl Default for LidarParams {
    fn default() -> Self {
        LidarParams {
            rays: 360,
            range: 3.0,
            noise_sigma: 0.01,
            eps: 0.3,
            min_points: 3,
            min_thickness: 0.05,
            max_vertices: MAX_VERTICES,
        }
    }
}

impl LidarParams {
    /// Checks every field; the error names the bad one and says why.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !(1..=100_000).contains(&self.rays) {
            return Err(("rays", "must be in 1..=100000".into()));
        }
        if !pos(self.range) {
            return Err(("range", "must be finite and > 0".into()));
        }
        if !(self.noise_sigma.is_finite() && self.noise_sigma >= 0.0) {
            return Err(("noise_sigma", "must be finite and >= 0".into()));
        }
        if !pos(self.eps) {
            return Err(("eps", "must be finite and > 0".into()));
        }
        if self.min_points == 0 {
            return Err(("min_points", "must be >= 1".into()));
        }
        if !pos(self.min_thickness) {
            return Err(("min_thickness", "must be finite and > 0".into()));
        }
        if !(4..=MAX_VERTICES).contains(&self.max_vertices) {
            return Err(("max_vertices", format!("must be in 4..={MAX_VERTICES}")));
        }
        Ok(())
    }
}

/// A simulated LiDAR with its own noise generator.
#[derive(Clone, Debug)]
pub struct Lidar {
    params: LidarParams,
    rng: ChaCha8Rng,
    noise: Option<Normal<f64>>,
}

impl Lidar {
    /// A LiDAR with validated `params`; its noise stream is seeded by `seed`.
    pub fn new(params: LidarParams, seed: u64) -> Result<Self, String> {
        params
            .validate()
            .map_err(|(f, m)| format!("lidar.{f}: {m}"))?;
        let noise = (params.noise_sigma > 0.0)
            .then(|| Normal::new(0.0, params.noise_sigma).expect("sigma is finite and > 0"));
        Ok(Lidar {
            params,
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x4c49_4441_525f_4e5a), // "LIDAR_NZ"
            noise,
        })
    }

    /// The settings.
    pub fn params(&self) -> &LidarParams {
        &self.params
    }

    /// One scan from `origin` (m) with the sensor's zero angle along `heading`
    /// (rad) against `obstacles` (the true map): the noisy hit points, m.
    pub fn scan(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        obstacles: &[Polygon],
    ) -> Vec<Vector2<f64>> {
        let n = self.params.rays;
        let mut out = Vec::with_capacity(n as usize);
        for i in 0..n {
            let a = heading + core::f64::consts::TAU * f64::from(i) / f64::from(n);
            let d = Vector2::new(a.cos(), a.sin());
            if let Some(t) = cast_ray(origin, d, obstacles, self.params.range) {
                let mut p = origin + d * t;
                if let Some(nz) = &self.noise {
                    p.x += nz.sample(&mut self.rng);
                    p.y += nz.sample(&mut self.rng);
                }
                out.push(p);
            }
        }
        out
    }

    /// A scan, clustered, as inferred obstacles (see the module docs).
    pub fn perceive(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        obstacles: &[Polygon],
    ) -> (Vec<Vector2<f64>>, Vec<Polygon>) {
        let points = self.scan(origin, heading, obstacles);
        let polys = infer_obstacles(&points, origin, &self.params);
        (points, polys)
    }
}

/// Distance along the unit direction `dir` from `origin` to the nearest crossing
/// of an obstacle edge, if within `range` (m).
pub fn cast_ray(
    origin: Vector2<f64>,
    dir: Vector2<f64>,
    obstacles: &[Polygon],
    range: f64,
) -> Option<f64> {
    let cross = |a: Vector2<f64>, b: Vector2<f64>| a.x * b.y - a.y * b.x;
    let mut best = f64::INFINITY;
    for poly in obstacles {
        let v = poly.vertices();
        // Skip polygons whose bounding circle is out of reach.
        let c = v.iter().fold(Vector2::zeros(), |s, p| s + p) / v.len() as f64;
        let r = v.iter().map(|p| (p - c).norm()).fold(0.0, f64::max);
        if (c - origin).norm() - r > range.min(best) {
            continue;
        }
        for k in 0..v.len() {
            let (a, b) = (v[k], v[(k + 1) % v.len()]);
            let e = b - a;
            let den = cross(dir, e);
            if den.abs() < 1e-15 {
                continue;
            }
            let w = a - origin;
            let t = cross(w, e) / den;
            let s = cross(w, dir) / den;
            if t >= 0.0 && (-1e-12..=1.0 + 1e-12).contains(&s) && t < best {
                best = t;
            }
        }
    }
    (best <= range).then_some(best)
}

/// DBSCAN labels: `Some(cluster)` (0-based, in order of discovery) or `None`
/// for noise. See the module docs for the rules.
pub fn dbscan(points: &[Vector2<f64>], eps: f64, min_points: usize) -> Vec<Option<usize>> {
    let n = points.len();
    let eps2 = eps * eps;
    let neighbours = |i: usize| -> Vec<usize> {
        (0..n)
            .filter(|&j| (points[j] - points[i]).norm_squared() <= eps2)
            .collect()
    };
    let mut label: Vec<Option<usize>> = vec![None; n];
    let mut visited = vec![false; n];
    let mut clusters = 0usize;
    for i in 0..n {
        if visited[i] {
            continue;
        }
        visited[i] = true;
        let nb = neighbours(i);
        if nb.len() < min_points {
            continue; // noise unless a later core point reaches it
        }
        let c = clusters;
        clusters += 1;
        label[i] = Some(c);
        let mut queue = nb;
        let mut head = 0;
        while head < queue.len() {
            let j = queue[head];
            head += 1;
            if label[j].is_none() {
                label[j] = Some(c);
            }
            if visited[j] {
                continue;
            }
            visited[j] = true;
            let nbj = neighbours(j);
            if nbj.len() >= min_points {
                queue.extend(nbj);
            }
        }
    }
    label
}

/// The points of each DBSCAN cluster, in cluster order.
pub fn clusters(points: &[Vector2<f64>], eps: f64, min_points: usize) -> Vec<Vec<Vector2<f64>>> {
    let labels = dbscan(points, eps, min_points);
    let k = labels.iter().flatten().max().map_or(0, |m| m + 1);
    let mut out = vec![Vec::new(); k];
    for (p, l) in points.iter().zip(&labels) {
        if let Some(c) = l {
            out[*c].push(*p);
        }
    }
    out
}

/// Inferred obstacles of a scan taken from `origin` (m, world frame): one
/// polygon per DBSCAN cluster, split where its polygon would come nearer to
/// the sensor than anything it saw (see [`visible_polygons`]).
pub fn infer_obstacles(
    points: &[Vector2<f64>],
    origin: Vector2<f64>,
    params: &LidarParams,
) -> Vec<Polygon> {
    let mut out = Vec::new();
    for c in clusters(points, params.eps, params.min_points) {
        visible_polygons(c, origin, params, &mut out);
    }
    out
}

/// Largest number of times a cluster is halved by [`visible_polygons`].
pub const MAX_SPLIT_DEPTH: u32 = 6;

/// The polygons of one cluster that are consistent with what the sensor saw.
///
/// Every hit point was seen from `origin` along a free ray, so no part of a
/// true obstacle is nearer to the sensor than the nearest point seen on it
/// (up to the noise and the sampling between rays). A cluster that joins the
/// points of two obstacles (their gap is below `eps`) can have a hull that
/// fills the free space between them, up to reaching around the robot, and
/// the controller would then be told that the robot stands in an obstacle
/// (seed 38 of `random` with LiDAR did exactly that before this check).
/// So the cluster's polygon ([`cluster_polygon`]) is kept only if it comes no
/// nearer to `origin` than its nearest point minus `3 noise_sigma +
/// min_thickness`; otherwise the cluster is cut in two where its points,
/// ordered by bearing from `origin`, are farthest apart (the seam between two
/// surfaces), and each half is treated the same way, at most
/// [`MAX_SPLIT_DEPTH`] times (then the pieces are kept as they are).
pub fn visible_polygons(
    points: Vec<Vector2<f64>>,
    origin: Vector2<f64>,
    params: &LidarParams,
    out: &mut Vec<Polygon>,
) {
    let mut stack = vec![(points, 0u32)];
    let slack = 3.0 * params.noise_sigma + params.min_thickness;
    while let Some((pts, depth)) = stack.pop() {
        let poly = cluster_polygon(&pts, params.min_thickness, params.max_vertices);
        let hides = || {
            let nearest_seen = pts
                .iter()
                .map(|p| (p - origin).norm())
                .fold(f64::INFINITY, f64::min);
            closest_point_point_polygon(&origin, &poly).signed_distance < nearest_seen - slack
        };
        if depth >= MAX_SPLIT_DEPTH || pts.len() < 2 || !hides() {
            out.push(poly);
            continue;
        }
        let (a, b) = split_at_seam(pts, origin);
        stack.push((a, depth + 1));
        stack.push((b, depth + 1));
    }
}

/// Two non-empty halves of `pts` (>= 2 points): ordered by bearing from
/// `origin` (measured from the direction of the points' mean, so a cluster
/// around the origin does not wrap), cut at the largest distance between
/// neighbours.
fn split_at_seam(
    mut pts: Vec<Vector2<f64>>,
    origin: Vector2<f64>,
) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    let mean = pts.iter().fold(Vector2::zeros(), |s, p| s + p) / pts.len() as f64 - origin;
    let base = mean.y.atan2(mean.x);
    let bearing = |p: &Vector2<f64>| {
        let d = p - origin;
        let a = d.y.atan2(d.x) - base;
        wrap_pi(a)
    };
    pts.sort_by(|p, q| bearing(p).total_cmp(&bearing(q)));
    let cut = (1..pts.len())
        .max_by(|&i, &j| {
            (pts[i] - pts[i - 1])
                .norm_squared()
                .total_cmp(&(pts[j] - pts[j - 1]).norm_squared())
        })
        .unwrap_or(pts.len() / 2);
    let b = pts.split_off(cut);
    (pts, b)
}

/// `a` wrapped into (-pi, pi].
fn wrap_pi(a: f64) -> f64 {
    use core::f64::consts::{PI, TAU};
    let w = a - TAU * (a / TAU).round();
    if w <= -PI { w + TAU } else { w }
}

fn cross3(o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
}

/// Convex hull, counter-clockwise, without collinear or repeated points
/// (Andrew's monotone chain). Returns fewer than 3 points for degenerate sets.
pub fn convex_hull(points: &[Vector2<f64>]) -> Vec<Vector2<f64>> {
    let mut p: Vec<Vector2<f64>> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup_by(|a, b| (*a - *b).norm() <= 1e-12);
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<Vector2<f64>> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vector2<f64>>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross3(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop(); // the last point starts the other chain
    }
    hull
}

/// Width of a convex polygon (CCW, >= 3 vertices): the smallest extent across
/// any of its edges, m.
fn width(h: &[Vector2<f64>]) -> f64 {
    let n = h.len();
    (0..n)
        .map(|i| {
            let (a, b) = (h[i], h[(i + 1) % n]);
            let e = (b - a).normalize();
            h.iter()
                .map(|p| (p - a).x * -e.y + (p - a).y * e.x)
                .fold(0.0, f64::max)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Conservative simplification of a CCW convex polygon to at most `max`
/// vertices: repeatedly remove the edge whose two neighbours, extended, meet
/// with the smallest added triangle. The result contains the input.
pub fn simplify_outer(hull: &[Vector2<f64>], max: usize) -> Vec<Vector2<f64>> {
    let mut h = hull.to_vec();
    while h.len() > max.max(3) {
        let n = h.len();
        let mut best: Option<(usize, Vector2<f64>, f64)> = None;
        for i in 0..n {
            // Edge (h[i], h[i+1]) collapses: extend (h[i-1], h[i]) and (h[i+1], h[i+2]).
            let (p0, p1, p2, p3) = (h[(i + n - 1) % n], h[i], h[(i + 1) % n], h[(i + 2) % n]);
            let (d1, d2) = (p1 - p0, p3 - p2);
            let den = d1.x * d2.y - d1.y * d2.x;
            if den <= 1e-15 {
                continue; // the extensions diverge (turn of pi or more)
            }
            let w = p2 - p1;
            let t = (w.x * d2.y - w.y * d2.x) / den;
            if t < 0.0 {
                continue;
            }
            let q = p1 + d1 * t;
            let area = 0.5 * cross3(p1, q, p2).abs();
            if best.is_none_or(|(_, _, a)| area < a) {
                best = Some((i, q, area));
            }
        }
        let Some((i, q, _)) = best else {
            break;
        };
        let j = (i + 1) % n;
        h[i] = q;
        h.remove(j);
    }
    h
}

/// The thin-obstacle rectangle of a point set: aligned with its longest chord
/// (x axis for a single point), containing every point with `thickness / 2` to
/// spare on every side.
fn thin_rectangle(points: &[Vector2<f64>], thickness: f64) -> Vec<Vector2<f64>> {
    let mut u = Vector2::new(1.0, 0.0);
    let mut best = 0.0;
    for (i, a) in points.iter().enumerate() {
        for b in &points[i + 1..] {
            let d = (b - a).norm();
            if d > best {
                best = d;
                u = (b - a) / d;
            }
        }
    }
    let w = Vector2::new(-u.y, u.x);
    let (mut l0, mut l1, mut w0, mut w1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in points {
        let (a, b) = (p.dot(&u), p.dot(&w));
        l0 = l0.min(a);
        l1 = l1.max(a);
        w0 = w0.min(b);
        w1 = w1.max(b);
    }
    let m = 0.5 * thickness;
    let (l0, l1, w0, w1) = (l0 - m, l1 + m, w0 - m, w1 + m);
    vec![
        u * l0 + w * w0,
        u * l1 + w * w0,
        u * l1 + w * w1,
        u * l0 + w * w1,
    ]
}

/// The obstacle inferred from one cluster (see the module docs): a valid convex
/// polygon that contains every point of the cluster. `points` must be non-empty
/// and finite.
pub fn cluster_polygon(
    points: &[Vector2<f64>],
    min_thickness: f64,
    max_vertices: usize,
) -> Polygon {
    let to_arr = |v: &[Vector2<f64>]| v.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>();
    let hull = convex_hull(points);
    if hull.len() >= 3 && width(&hull) >= min_thickness {
        let h = simplify_outer(&hull, max_vertices.clamp(4, MAX_VERTICES));
        if let Ok(p) = Polygon::new(&to_arr(&h)) {
            return p;
        }
    }
    let rect = thin_rectangle(points, min_thickness);
    Polygon::new(&to_arr(&rect)).expect("a rectangle with positive sides is a convex polygon")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    #[test]
    fn hull_drops_interior_and_collinear_points() {
        let pts = [
            v(0.0, 0.0),
            v(1.0, 0.0),
            v(0.5, 0.0),
            v(1.0, 1.0),
            v(0.0, 1.0),
            v(0.5, 0.5),
        ];
        let h = convex_hull(&pts);
        assert_eq!(h.len(), 4);
        assert_eq!(h[0], v(0.0, 0.0));
        assert_eq!(
            convex_hull(&[v(0.0, 0.0), v(1.0, 1.0), v(2.0, 2.0)]).len(),
            2
        );
    }

    #[test]
    fn simplification_contains_the_input() {
        let circle: Vec<_> = (0..100)
            .map(|i| {
                let a = core::f64::consts::TAU * f64::from(i) / 100.0;
                v(a.cos(), a.sin())
            })
            .collect();
        let s = simplify_outer(&convex_hull(&circle), 12);
        assert_eq!(s.len(), 12);
        let poly = Polygon::new(&s.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>()).unwrap();
        for p in &circle {
            assert!(poly.contains(p));
        }
    }
}
