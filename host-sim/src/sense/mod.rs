//! Perception for unknown maps (docs/maths.md §6): a simulated 2D LiDAR, DBSCAN
//! clustering of its hit points, and convex pieces that hug the points of each
//! cluster without ever covering space the sensor has seen to be free.
//! A room of the simulator that uses only [`crate::world`]; its settings are
//! the scenario's `[lidar]` table ([`LidarParams`]).
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
//!   dropped. Neighbours through a grid of `eps` cells, each point queued
//!   once: O(n) memory, O(n k) time for k neighbours per point (the ROS 2
//!   node caps the rays of a scan, docs/ros2.md).
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
//! Guarantee (tested by a property test in `host-sim/tests/perception_free_space.rs`): no
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
//! [`cluster_polygon`] (one convex hull per cluster, the controller's
//! [`convex_hull_into`](ldcbf_controller::convex_hull_into),
//! thin clusters as rectangles, conservative simplification to `max_vertices`)
//! is the former inference: it is kept as a utility, but its hull of a cluster
//! that spans a corner covers free space, sometimes the robot (issue 11).
//!
//! The controller then sees only these inferred polygons; the simulator still
//! measures clearance against the true ones.

use ldcbf_controller::nalgebra::Vector2;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::world::setting::SettingError;
use crate::world::{MAX_VERTICES, Polygon};

mod assign;
mod dbscan;
pub mod detect;
pub mod faces;
mod infer;
mod map;
pub mod movers;
#[cfg(test)]
mod patterns;
#[cfg(test)]
mod tests;
pub mod track;
pub mod walls;

pub use dbscan::{clusters, dbscan};
pub use infer::{
    cluster_polygon, free_tolerance, infer_obstacles, simplify_outer, split_and_merge,
};
pub use map::{CellState, Growth, MapParams, OccupancyMap};

/// Obstacle perception (docs/maths.md §6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Perception {
    /// The controller gets the true obstacle polygons.
    #[default]
    Known,
    /// The controller gets only the obstacles inferred from a simulated LiDAR
    /// by DBSCAN ([`crate::sense`]).
    Lidar,
}

impl Perception {
    /// The name used in files (`known`, `lidar`).
    pub fn name(self) -> &'static str {
        match self {
            Perception::Known => "known",
            Perception::Lidar => "lidar",
        }
    }
}

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
    /// Track the person-sized clusters of each scan, keep those that may
    /// move out of the map and give them to the controller with their
    /// velocities ([`movers`], [`track`]; off = every hit goes to the map,
    /// every obstacle at rest).
    pub track_moving: bool,
    /// The occupancy map built from the scans (the `[lidar.map]` table,
    /// [`MapParams`]); its pieces are the controller's obstacles.
    pub map: MapParams,
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
            track_moving: false,
            map: MapParams::default(),
        }
    }
}

impl LidarParams {
    /// Checks every field; the error names the bad one and says why.
    pub fn validate(&self) -> Result<(), SettingError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !(1..=100_000).contains(&self.rays) {
            return Err(SettingError::new("rays", "must be in 1..=100000"));
        }
        if !pos(self.range) {
            return Err(SettingError::new("range", "must be finite and > 0"));
        }
        if !(self.noise_sigma.is_finite() && self.noise_sigma >= 0.0) {
            return Err(SettingError::new("noise_sigma", "must be finite and >= 0"));
        }
        if !pos(self.eps) {
            return Err(SettingError::new("eps", "must be finite and > 0"));
        }
        if self.min_points == 0 {
            return Err(SettingError::new("min_points", "must be >= 1"));
        }
        if !pos(self.min_thickness) {
            return Err(SettingError::new("min_thickness", "must be finite and > 0"));
        }
        if !(4..=MAX_VERTICES).contains(&self.max_vertices) {
            return Err(SettingError::new(
                "max_vertices",
                format!("must be in 4..={MAX_VERTICES}"),
            ));
        }
        let b = self.breakpoint_angle;
        if !(b.is_finite() && b > 0.0 && b < core::f64::consts::FRAC_PI_2) {
            return Err(SettingError::new(
                "breakpoint_angle",
                "must be in (0, pi/2) rad",
            ));
        }
        if !pos(self.line_tolerance) {
            return Err(SettingError::new(
                "line_tolerance",
                "must be finite and > 0",
            ));
        }
        if self.line_tolerance < 4.0 * self.noise_sigma {
            return Err(SettingError::new(
                "line_tolerance",
                format!(
                    "must be at least 4 noise_sigma = {} m (noise alone would cut straight walls into pieces)",
                    4.0 * self.noise_sigma
                ),
            ));
        }
        if !(self.free_margin.is_finite() && self.free_margin >= 0.0) {
            return Err(SettingError::new("free_margin", "must be finite and >= 0"));
        }
        self.map.validate()
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
        params.validate().map_err(|e| format!("lidar.{e}"))?;
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
