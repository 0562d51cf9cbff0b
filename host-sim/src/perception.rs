//! Perception for unknown maps (SPEC 6, report 5.2): a simulated 2D LiDAR, DBSCAN
//! clustering of its hit points, and convex pieces that hug the points of each
//! cluster without ever covering space the sensor has seen to be free.
//!
//! World frame W, metres, radians. The sensor sits at the CoM.
//!
//! * [`Lidar::scan_rays`]: `rays` rays from the sensor, ray `i` at angle
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
//! * [`infer_obstacles`]: each cluster is cut into convex pieces, in the scan's
//!   own order (one sensor, rays sorted by angle). The method is the classic
//!   line-extraction pipeline for 2D range scans:
//!   1. **Breakpoints** (adaptive breakpoint detector, G. A. Borges and M.-J.
//!      Aldon, "Line extraction in 2D range images for mobile robotics",
//!      J. Intelligent and Robotic Systems 40, 2004): consecutive rays `j-1`,
//!      `j` belong to one chain when both hit points are in the same DBSCAN
//!      cluster and
//!      `|p_j - p_(j-1)| <= r_(j-1) sin(dphi) / sin(lambda - dphi) + 3 sqrt(2) noise_sigma`
//!      (`r` the range, `dphi` the ray spacing, `lambda` =
//!      `breakpoint_angle`: a surface seen at less than `lambda` of incidence
//!      is cut; `sqrt 2` because both points are noisy). A missed ray, a
//!      DBSCAN noise point or a hit nearer than the free-space tolerance (below)
//!      ends a chain.
//!   2. **Split and merge** (Iterative End Point Fit, "split-and-merge" in
//!      V. Nguyen, A. Martinelli, N. Tomatis, R. Siegwart, "A comparison of line
//!      extraction algorithms using 2D laser rangefinder for indoor mobile
//!      robotics", IROS 2005; the same scheme as ROS `laser_line_extraction`):
//!      a chain is split at the point farthest from the chord between its end
//!      points while that distance exceeds `line_tolerance`, recursively (the
//!      split point belongs to both halves); then neighbouring segments are
//!      merged while the total-least-squares line of their union stays within
//!      `line_tolerance` of every point, so a straight wall stays one piece.
//!   3. **Pieces extruded away from the sensor** (`segment_piece`): a segment
//!      covering rays `a..=b` becomes the quadrilateral cut from the angular
//!      sector of those rays (bounded by the rays at `angle(a) - h` and
//!      `angle(b) + h`, `h = min(dphi / 2, 0.25)`, so the neighbouring rays are
//!      outside it) by two lines parallel to the segment's fitted line: the near
//!      line, as close to the sensor as it can be without crossing the seen free
//!      part of any ray in the sector (only the segment's own rays are), and the far line `min_thickness` behind
//!      the farthest point. A ray counts as seen free up to `3 noise_sigma +
//!      free_margin` short of its hit point. A segment whose sector is too wide
//!      or too oblique to its line for this (a ray within about 84 degrees of the
//!      line's normal is required) is halved, down to single rays, whose piece
//!      is normal to the ray.
//!   4. **Convex merge**: neighbouring pieces of a cluster (adjacent rays, also
//!      across a breakpoint) are replaced by their
//!      convex hull, trimmed where a ray of their joint sector enters it by at
//!      most `line_tolerance` (noise), and kept apart when one enters deeper
//!      (see `merge_pieces`): a convex obstacle seen from outside (a box
//!      corner, a blob) is one piece again, a concave corner (inside a U, two
//!      walls meeting) stays cut. This keeps the obstacle count per scan near
//!      that of one hull per cluster (the controller keeps only the nearest
//!      few).
//!
//! Guarantee (tested by a property test in `tests/sim_perception.rs`): no
//! piece contains the sensor, and for every ray the segment from the sensor
//! along the ray's direction to its measured range (the distance of its hit
//! point) shortened by `3 noise_sigma + free_margin`, or to `range` when it
//! hit nothing, does not enter any piece's interior. The seen free part of a
//! ray is taken along the ray's own direction, not toward its noisy hit point:
//! the per-axis noise turns into a bearing error (about 2 degrees at 0.3 m,
//! more than the ray spacing), and a neighbouring ray's noisy point would
//! otherwise fall inside a needle tip's sector and push its piece back behind
//! the tip, i.e. hide an obstacle pointing at the robot. So the controller is
//! never told that free space it saw (nor the robot's own position) is an
//! obstacle, whatever the clusters join: a U-shaped cup, two walls meeting at a
//! corner. The price: a piece holds its points only up to the noise (a point
//! in front of the near line by at most the noise and the line tolerance), and
//! across the rays a piece is only as wide as the rays it covers (a single
//! ray near the sensor gives a piece a few mm wide and `min_thickness` deep).
//!
//! [`cluster_polygon`] (one convex hull per cluster, Andrew's monotone chain,
//! thin clusters as rectangles, conservative simplification to `max_vertices`)
//! is the former inference: it is kept as a utility, but its hull of a cluster
//! that spans a corner covers free space, sometimes the robot (issue 11).
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
    /// Largest vertex count of an inferred polygon (at most 32; the pieces of
    /// [`infer_obstacles`] have 4, [`cluster_polygon`] uses up to this many).
    pub max_vertices: usize,
    /// Adaptive breakpoint detector's `lambda`, rad: the smallest incidence
    /// angle between a ray and a surface at which two consecutive hits still
    /// belong to one chain. In `(0, pi/2)`; with `lambda <= 2 pi / rays` only
    /// missed rays and cluster changes cut chains.
    pub breakpoint_angle: f64,
    /// Split-and-merge tolerance, m: largest distance of a point from its
    /// segment's line (chord while splitting, fitted line while merging). At
    /// least `4 noise_sigma` (checked): the largest of a few hundred hits'
    /// distances from their true line is about `3.5 noise_sigma`, and a
    /// tolerance below that lets the noise alone cut a straight wall into
    /// pieces. The pieces' ends then give the controller half-planes across
    /// the path (each obstacle's half-plane is taken at its point nearest the
    /// robot), which made every LiDAR run down a 0.62-0.74 m corridor relax
    /// safety and touch a wall at the former default of 0.03 m; at 0.05 m the
    /// same runs keep the clearances of the known map.
    pub line_tolerance: f64,
    /// Free-space margin, m: a ray is taken as seen free up to `3 noise_sigma
    /// + free_margin` short of its hit point; no piece reaches into that part.
    pub free_margin: f64,
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
            breakpoint_angle: 10f64.to_radians(),
            line_tolerance: 0.05,
            free_margin: 0.005,
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
        let b = self.breakpoint_angle;
        if !(b.is_finite() && b > 0.0 && b < core::f64::consts::FRAC_PI_2) {
            return Err(("breakpoint_angle", "must be in (0, pi/2) rad".into()));
        }
        if !pos(self.line_tolerance) {
            return Err(("line_tolerance", "must be finite and > 0".into()));
        }
        if self.line_tolerance < 4.0 * self.noise_sigma {
            return Err((
                "line_tolerance",
                format!(
                    "must be at least 4 noise_sigma = {} m (noise alone would cut straight walls into pieces)",
                    4.0 * self.noise_sigma
                ),
            ));
        }
        if !(self.free_margin.is_finite() && self.free_margin >= 0.0) {
            return Err(("free_margin", "must be finite and >= 0".into()));
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
    /// (rad) against `obstacles` (the true map), one entry per ray in ray
    /// order: the noisy hit point (m) or `None` when nothing is within range.
    pub fn scan_rays(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        obstacles: &[Polygon],
    ) -> Vec<Option<Vector2<f64>>> {
        let n = self.params.rays;
        let mut out = Vec::with_capacity(n as usize);
        for i in 0..n {
            let d = ray_direction(heading, i as usize, n as usize);
            out.push(cast_ray(origin, d, obstacles, self.params.range).map(|t| {
                let mut p = origin + d * t;
                if let Some(nz) = &self.noise {
                    p.x += nz.sample(&mut self.rng);
                    p.y += nz.sample(&mut self.rng);
                }
                p
            }));
        }
        out
    }

    /// The hit points of [`Lidar::scan_rays`] (missed rays left out), m.
    pub fn scan(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        obstacles: &[Polygon],
    ) -> Vec<Vector2<f64>> {
        self.scan_rays(origin, heading, obstacles)
            .into_iter()
            .flatten()
            .collect()
    }

    /// A scan and the obstacles inferred from it ([`infer_obstacles`]): the
    /// hit points (m, ray order) and the pieces (world frame).
    pub fn perceive(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        obstacles: &[Polygon],
    ) -> (Vec<Vector2<f64>>, Vec<Polygon>) {
        let rays = self.scan_rays(origin, heading, obstacles);
        let polys = infer_obstacles(&rays, origin, heading, &self.params);
        (rays.into_iter().flatten().collect(), polys)
    }
}

/// Unit direction of ray `i` of `n` (world frame) for a sensor heading
/// `heading` (rad): angle `heading + 2 pi i / n`.
pub fn ray_direction(heading: f64, i: usize, n: usize) -> Vector2<f64> {
    let a = ray_angle(heading, i, n);
    Vector2::new(a.cos(), a.sin())
}

/// Angle of ray `i` of `n` (rad, `i` may exceed `n` to unwrap a chain).
fn ray_angle(heading: f64, i: usize, n: usize) -> f64 {
    heading + core::f64::consts::TAU * i as f64 / n as f64
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

/// Inferred obstacles of one scan taken from `origin` (m, world frame) with
/// the sensor's zero angle along `heading` (rad): `rays[i]` is ray `i`'s hit
/// point (m) or `None` (see [`Lidar::scan_rays`]). The convex pieces of every
/// DBSCAN cluster, by breakpoints, split-and-merge and extrusion away from the
/// sensor (module docs). Deterministic: the same scan gives the same pieces.
pub fn infer_obstacles(
    rays: &[Option<Vector2<f64>>],
    origin: Vector2<f64>,
    heading: f64,
    params: &LidarParams,
) -> Vec<Polygon> {
    let n = rays.len();
    if n == 0 {
        return Vec::new();
    }
    let tol = free_tolerance(params);
    // Hits far enough from the sensor to be kept out of a piece, and DBSCAN
    // over them.
    let usable: Vec<usize> = (0..n)
        .filter(|&i| rays[i].is_some_and(|p| (p - origin).norm() > tol + 1e-3))
        .collect();
    let pts: Vec<Vector2<f64>> = usable.iter().map(|&i| rays[i].unwrap_or(origin)).collect();
    let mut label: Vec<Option<usize>> = vec![None; n];
    for (k, l) in dbscan(&pts, params.eps, params.min_points)
        .into_iter()
        .enumerate()
    {
        label[usable[k]] = l;
    }
    let dphi = core::f64::consts::TAU / n as f64;
    let lambda = params.breakpoint_angle;
    let linked = |a: usize, b: usize| -> bool {
        let (Some(la), Some(lb)) = (label[a], label[b]) else {
            return false;
        };
        let (Some(pa), Some(pb)) = (rays[a], rays[b]) else {
            return false;
        };
        if la != lb {
            return false;
        }
        if lambda <= dphi || n < 3 {
            return true;
        }
        let ra = (pa - origin).norm();
        let dmax = ra * dphi.sin() / (lambda - dphi).sin()
            + 3.0 * core::f64::consts::SQRT_2 * params.noise_sigma;
        (pb - pa).norm() <= dmax
    };
    // Start where a chain starts (a ray not linked to its predecessor), so
    // that no chain wraps past the end of the scan; 0 if all are linked.
    let start = (0..n).find(|&i| !linked((i + n - 1) % n, i)).unwrap_or(0);
    let mut chains: Vec<Vec<usize>> = Vec::new(); // unwrapped ray indices
    let mut cur: Vec<usize> = Vec::new();
    for u in start..start + n {
        let i = u % n;
        if label[i].is_none() {
            if !cur.is_empty() {
                chains.push(std::mem::take(&mut cur));
            }
            continue;
        }
        if let Some(&last) = cur.last()
            && !linked(last % n, i)
        {
            chains.push(std::mem::take(&mut cur));
        }
        cur.push(u);
    }
    if !cur.is_empty() {
        chains.push(cur);
    }
    let mut out = Vec::new();
    let ctx = PieceContext {
        origin,
        heading,
        rays: n,
        tol,
        params,
    };
    let mut pieces: Vec<(Option<usize>, Piece)> = Vec::new();
    for chain in chains {
        let p: Vec<Vector2<f64>> = chain.iter().filter_map(|&u| rays[u % n]).collect();
        let mut segs = Vec::new();
        for (a, b) in split_and_merge(&p, params.line_tolerance) {
            segment_piece(&ctx, &chain[a..=b], &p[a..=b], &mut segs);
        }
        let l = label[chain[0] % n];
        pieces.extend(segs.into_iter().map(|s| (l, s)));
    }
    // Step 4: neighbouring pieces of one cluster (adjacent rays, across
    // breakpoints too) whose trimmed convex hull keeps out of the free space
    // of every ray of their sectors become one piece.
    let point = |u: usize| rays[u % n];
    let mut cur: Option<(Option<usize>, Piece)> = None;
    for (l, next) in pieces {
        let Some((lc, c)) = cur.take() else {
            cur = Some((l, next));
            continue;
        };
        let merged = (lc == l && next.first <= c.last + 1)
            .then(|| merge_pieces(&ctx, &c, &next, point))
            .flatten();
        match merged {
            Some(m) => cur = Some((l, m)),
            None => {
                out.push(c.poly);
                cur = Some((l, next));
            }
        }
    }
    out.extend(cur.map(|(_, c)| c.poly));
    out
}

/// A convex piece, the unwrapped ray indices of its sector, and for each of
/// those rays the normal (away from the sensor) of the segment piece it came
/// from.
struct Piece {
    first: usize,
    last: usize,
    poly: Polygon,
    normals: Vec<Vector2<f64>>,
}

/// The convex hull of two neighbouring pieces of one chain (`b` after `a`),
/// trimmed where it enters seen free space, if it is a valid piece.
///
/// For every ray of the joint sector whose free part (along its direction,
/// to its range `range(u)` minus the free-space tolerance) enters the hull,
/// the hull is cut by the line through that free part's end, parallel to the
/// ray's own segment (its normal `w` has `w . d > 0`, so the whole free part
/// lies on the cut-away side). The merge is refused when a ray entered deeper
/// than `line_tolerance` (the hull bridges a concave corner: the pieces stay
/// apart), when a hit point (`point(u)`, m) ends up farther than 1 mm more
/// from the merged piece than from its own piece, when the sector is wider
/// than [`MAX_SECTOR`], or when the result has more than `max_vertices`
/// vertices. Rays outside the sector never enter: the hull lies inside the
/// sector.
fn merge_pieces(
    ctx: &PieceContext<'_>,
    a: &Piece,
    b: &Piece,
    point: impl Fn(usize) -> Option<Vector2<f64>>,
) -> Option<Piece> {
    let range = |u: usize| point(u).map_or(0.0, |q| (q - ctx.origin).norm());
    let (first, last) = (a.first, b.last.max(a.last));
    let n = ctx.rays;
    let h = (0.5 * core::f64::consts::TAU / n as f64).min(0.25);
    let span = ray_angle(ctx.heading, last, n) - ray_angle(ctx.heading, first, n) + 2.0 * h;
    if span > MAX_SECTOR || b.first < a.first {
        return None;
    }
    let normals: Vec<Vector2<f64>> = (first..=last)
        .map(|u| {
            if u <= a.last {
                a.normals[u - a.first]
            } else {
                b.normals[u - b.first]
            }
        })
        .collect();
    let pts: Vec<Vector2<f64>> = a
        .poly
        .vertices()
        .iter()
        .chain(b.poly.vertices())
        .copied()
        .collect();
    let mut hull = convex_hull(&pts);
    for u in first..=last {
        let d = ray_direction(ctx.heading, u, n);
        let free = range(u) - ctx.tol;
        if free <= 0.0 {
            continue;
        }
        let Some(t_in) = ray_entry(&hull, ctx.origin, d, free) else {
            continue;
        };
        if free - t_in > ctx.params.line_tolerance {
            return None;
        }
        let w = normals[u - first];
        let e = ctx.origin + d * free;
        hull = clip_half_plane(&hull, w, w.dot(&e));
        if hull.len() < 3 {
            return None;
        }
    }
    if hull.len() > ctx.params.max_vertices.min(MAX_VERTICES) {
        return None;
    }
    // Cuts only shrink the hull; check every ray once more all the same.
    for u in first..=last {
        let free = range(u) - ctx.tol;
        if free > 0.0
            && ray_entry(&hull, ctx.origin, ray_direction(ctx.heading, u, n), free).is_some()
        {
            return None;
        }
    }
    let arr: Vec<[f64; 2]> = hull.iter().map(|p| [p.x, p.y]).collect();
    let poly = Polygon::new(&arr).ok()?;
    // The cuts must not lose points: each hit stays as near to the merged
    // piece as it was to its own (up to 1 mm).
    let dist = |q: &Polygon, p: &Vector2<f64>| closest_point_point_polygon(p, q).signed_distance;
    for u in first..=last {
        if let Some(p) = point(u) {
            let own = dist(&a.poly, &p).min(dist(&b.poly, &p));
            if dist(&poly, &p) > own.max(0.0) + 1e-3 {
                return None;
            }
        }
    }
    Some(Piece {
        first,
        last,
        poly,
        normals,
    })
}

/// The part of the CCW convex polygon `h` where `w . x >= c`
/// (Sutherland-Hodgman against one line), CCW.
fn clip_half_plane(h: &[Vector2<f64>], w: Vector2<f64>, c: f64) -> Vec<Vector2<f64>> {
    let mut out = Vec::with_capacity(h.len() + 1);
    for i in 0..h.len() {
        let (p, q) = (h[i], h[(i + 1) % h.len()]);
        let (fp, fq) = (w.dot(&p) - c, w.dot(&q) - c);
        if fp >= 0.0 {
            out.push(p);
        }
        if (fp >= 0.0) != (fq >= 0.0) {
            out.push(p + (q - p) * (fp / (fp - fq)));
        }
    }
    convex_hull(&out)
}

/// Where the segment from `o` along the unit direction `d` to length `len`
/// (m) first gets more than 1e-10 m into the interior of the CCW convex
/// polygon `h`, if it does: the distance from `o` (Cyrus-Beck clipping).
fn ray_entry(h: &[Vector2<f64>], o: Vector2<f64>, d: Vector2<f64>, len: f64) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, len);
    for i in 0..h.len() {
        let (p, q) = (h[i], h[(i + 1) % h.len()]);
        let e = (q - p).normalize();
        let nrm = Vector2::new(-e.y, e.x); // inward for CCW
        let f0 = nrm.dot(&(o - p)) - 1e-10;
        let fd = nrm.dot(&d);
        if fd.abs() < 1e-15 {
            if f0 <= 0.0 {
                return None;
            }
            continue;
        }
        let t = -f0 / fd;
        if fd > 0.0 {
            t0 = t0.max(t);
        } else {
            t1 = t1.min(t);
        }
        if t0 >= t1 {
            return None;
        }
    }
    Some(t0)
}

/// How far short of its hit a ray is taken as seen free, m:
/// `3 noise_sigma + free_margin`.
pub fn free_tolerance(params: &LidarParams) -> f64 {
    3.0 * params.noise_sigma + params.free_margin
}

/// Split and merge (Iterative End Point Fit) of an ordered point chain: the
/// segments as inclusive index ranges `(a, b)` into `points`, in order,
/// neighbours sharing their end point. See the module docs.
pub fn split_and_merge(points: &[Vector2<f64>], tolerance: f64) -> Vec<(usize, usize)> {
    if points.is_empty() {
        return Vec::new();
    }
    // Split.
    let mut done: Vec<(usize, usize)> = Vec::new();
    let mut stack = vec![(0usize, points.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        let far = (a + 1..b)
            .map(|k| (k, chord_distance(points[a], points[b], points[k])))
            .max_by(|x, y| x.1.total_cmp(&y.1));
        match far {
            Some((k, d)) if d > tolerance => {
                stack.push((k, b)); // popped after (a, k): order kept
                stack.push((a, k));
            }
            _ => done.push((a, b)),
        }
    }
    // Merge neighbours whose union still fits one line.
    let mut merged: Vec<(usize, usize)> = Vec::with_capacity(done.len());
    for (a, b) in done {
        if let Some(last) = merged.last_mut()
            && line_fit(&points[last.0..=b]).2 <= tolerance
        {
            last.1 = b;
            continue;
        }
        merged.push((a, b));
    }
    merged
}

/// Distance of `p` from the line through `a` and `b` (from `a` when they
/// coincide), m.
fn chord_distance(a: Vector2<f64>, b: Vector2<f64>, p: Vector2<f64>) -> f64 {
    let e = b - a;
    let l = e.norm();
    if l < 1e-12 {
        return (p - a).norm();
    }
    (e.x * (p - a).y - e.y * (p - a).x).abs() / l
}

/// Total-least-squares line of `points` (>= 1): centroid, unit direction and
/// the largest distance of a point from the line (m). One point: direction x.
fn line_fit(points: &[Vector2<f64>]) -> (Vector2<f64>, Vector2<f64>, f64) {
    let m = points.len() as f64;
    let c = points.iter().fold(Vector2::zeros(), |s, p| s + p) / m;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let d = p - c;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let th = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let u = Vector2::new(th.cos(), th.sin());
    let res = points
        .iter()
        .map(|p| (u.x * (p - c).y - u.y * (p - c).x).abs())
        .fold(0.0, f64::max);
    (c, u, res)
}

/// What [`segment_piece`] needs besides the segment.
struct PieceContext<'a> {
    origin: Vector2<f64>,
    heading: f64,
    rays: usize,
    tol: f64,
    params: &'a LidarParams,
}

/// Smallest cosine between the piece's line normal and a ray of its sector.
const MIN_NORMAL_COS: f64 = 0.1;

/// Largest angular width of a piece's sector, rad.
const MAX_SECTOR: f64 = 0.8 * core::f64::consts::PI;

/// The piece of one segment (module docs, step 3), pushed to `out`: the
/// segment covers the unwrapped ray indices `idx` with hit points `pts` (same
/// length, >= 1). Halved (recursively) when its sector is too wide or too
/// oblique to its fitted line.
fn segment_piece(
    ctx: &PieceContext<'_>,
    idx: &[usize],
    pts: &[Vector2<f64>],
    out: &mut Vec<Piece>,
) {
    let o = ctx.origin;
    let n = ctx.rays;
    let dphi = core::f64::consts::TAU / n as f64;
    let h = (0.5 * dphi).min(0.25);
    let (first, last) = (idx[0], idx[idx.len() - 1]);
    let (tl, tr) = (
        ray_angle(ctx.heading, first, n) - h,
        ray_angle(ctx.heading, last, n) + h,
    );
    let (bl, br) = (
        Vector2::new(tl.cos(), tl.sin()),
        Vector2::new(tr.cos(), tr.sin()),
    );
    // The normal: of the fitted line (2+ points), else along the ray.
    let mut w = if pts.len() >= 2 {
        let (_, u, _) = line_fit(pts);
        Vector2::new(-u.y, u.x)
    } else {
        ray_direction(ctx.heading, first, n)
    };
    let mid = pts.iter().fold(Vector2::zeros(), |s, p| s + p) / pts.len() as f64 - o;
    if w.dot(&mid) < 0.0 {
        w = -w;
    }
    let ok = tr - tl <= MAX_SECTOR && w.dot(&bl) >= MIN_NORMAL_COS && w.dot(&br) >= MIN_NORMAL_COS;
    if !ok {
        if pts.len() >= 2 {
            let k = pts.len() / 2;
            segment_piece(ctx, &idx[..k], &pts[..k], out);
            segment_piece(ctx, &idx[k..], &pts[k..], out);
        }
        // A single ray always passes: w is its direction, the sector is
        // at most 0.5 rad wide.
        return;
    }
    // Near line: no seen-free ray part of the sector (its own rays, along
    // their directions, to their ranges minus `tol`) crosses it.
    let mut near = 1e-3f64;
    for (&j, p) in idx.iter().zip(pts) {
        let r = (p - o).norm();
        near = near.max(w.dot(&ray_direction(ctx.heading, j, n)) * (r - ctx.tol));
    }
    let far = pts.iter().map(|p| w.dot(&(p - o))).fold(near, f64::max) + ctx.params.min_thickness;
    let at = |b: Vector2<f64>, c: f64| o + b * (c / w.dot(&b));
    let quad = [at(bl, near), at(br, near), at(br, far), at(bl, far)];
    let arr: Vec<[f64; 2]> = quad.iter().map(|p| [p.x, p.y]).collect();
    // The quadrilateral has positive area (near < far, tl < tr); a sliver
    // below the polygon tolerances (a sector of nanometres) is dropped.
    if let Ok(p) = Polygon::new(&arr) {
        out.push(Piece {
            first,
            last,
            poly: p,
            normals: vec![w; last - first + 1],
        });
    }
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

    fn poly(pts: &[[f64; 2]]) -> Polygon {
        Polygon::new(pts).unwrap()
    }

    #[test]
    fn perception_keeps_a_convex_box_whole_and_cuts_an_inside_corner() {
        let params = LidarParams::default();
        let o = v(0.0, 0.0);
        // A square seen corner-first (a diamond): two faces, one piece.
        let diamond = [poly(&[[1.5, 0.0], [2.0, -0.5], [2.5, 0.0], [2.0, 0.5]])];
        let rays = Lidar::new(params.clone(), 7)
            .unwrap()
            .scan_rays(o, 0.0, &diamond);
        let pts: Vec<_> = rays.iter().flatten().copied().collect();
        assert!(pts.len() > 20);
        let pieces = infer_obstacles(&rays, o, 0.0, &params);
        assert_eq!(pieces.len(), 1, "{pieces:?}");
        // Two walls meeting in an L around the sensor: one DBSCAN cluster,
        // whose hull covers the corner's free space; the pieces do not.
        let l = [
            poly(&[[-1.0, 0.5], [1.05, 0.5], [1.05, 0.55], [-1.0, 0.55]]),
            poly(&[[1.0, -1.0], [1.05, -1.0], [1.05, 0.55], [1.0, 0.55]]),
        ];
        let rays = Lidar::new(params.clone(), 7).unwrap().scan_rays(o, 0.3, &l);
        let pts: Vec<_> = rays.iter().flatten().copied().collect();
        let cl = clusters(&pts, params.eps, params.min_points);
        assert_eq!(cl.len(), 1);
        let free = v(0.7, 0.2); // on the ray toward (1, 0.29), 0.3 m short of the wall
        assert!(cluster_polygon(&cl[0], 0.05, 32).contains(&free));
        let pieces = infer_obstacles(&rays, o, 0.3, &params);
        assert!(pieces.len() >= 2, "{pieces:?}");
        for q in &pieces {
            assert!(!q.contains(&o) && !q.contains(&free), "{:?}", q.vertices());
        }
        // Deterministic and seeded: the same seed, the same pieces.
        let again = Lidar::new(params.clone(), 7).unwrap().scan_rays(o, 0.3, &l);
        assert_eq!(infer_obstacles(&again, o, 0.3, &params), pieces);
    }

    #[test]
    fn lidar_params_validate_the_new_fields() {
        let ok = LidarParams::default();
        assert!(ok.validate().is_ok());
        let bad = |p: LidarParams| p.validate().unwrap_err().0;
        let b = LidarParams {
            breakpoint_angle: 2.0,
            ..ok.clone()
        };
        assert_eq!(bad(b), "breakpoint_angle");
        let b = LidarParams {
            line_tolerance: 0.0,
            ..ok.clone()
        };
        assert_eq!(bad(b), "line_tolerance");
        // Below 4 noise_sigma the noise alone splits straight walls.
        let b = LidarParams {
            noise_sigma: 0.02,
            ..ok.clone()
        };
        assert_eq!(bad(b), "line_tolerance");
        let b = LidarParams {
            noise_sigma: 0.02,
            line_tolerance: 0.08,
            ..ok.clone()
        };
        assert!(b.validate().is_ok());
        let b = LidarParams {
            free_margin: -1.0,
            ..ok
        };
        assert_eq!(bad(b), "free_margin");
    }
}
