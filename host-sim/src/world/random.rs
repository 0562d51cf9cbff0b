//! Seeded random obstacles: the paper's random test (convex hulls of random
//! points, the `[generator]` table of a scenario file with `kind =
//! "random_polygons"`), regular polygons, and the distance between two
//! polygons. The layout families are [`crate::world::families`].
//!
//! All coordinates are in the world frame W, metres.

use ldcbf_controller::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::world::setting::SettingError;
use crate::world::{MAX_VERTICES, Polygon};

/// Parameters of the seeded random-obstacle generator (the `[generator]` table;
/// the paper's random test by default: 8 convex polygons in the 10 m x 10 m
/// square, start and goal kept clear by 1 m).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RandomParams {
    /// Generator kind: `"random_polygons"` (the fields below), or a family of
    /// [`crate::world::families`] (`corridor`, `doorway`, `cup`, `wall_start`,
    /// `clutter`, `thin`), which draws the start, heading, goal and obstacles
    /// itself and ignores the other fields.
    #[serde(default = "default_kind")]
    pub kind: String,
    /// Number of polygons: at most [`MAX_COUNT`], or [`MAX_COUNT_WITH_GAP`]
    /// with `min_gap > 0` (each polygon is then checked against every earlier
    /// one).
    #[serde(default = "default_count")]
    pub count: usize,
    /// Lower-left corner of the area where centres are drawn, m.
    #[serde(
        default = "default_area_min",
        deserialize_with = "crate::world::exact::exact"
    )]
    pub area_min: [f64; 2],
    /// Upper-right corner of that area, m.
    #[serde(
        default = "default_area_max",
        deserialize_with = "crate::world::exact::exact"
    )]
    pub area_max: [f64; 2],
    /// Range of the circumradius `[min, max]`, m.
    #[serde(
        default = "default_radius",
        deserialize_with = "crate::world::exact::exact"
    )]
    pub radius: [f64; 2],
    /// Range of the number of sampled points `[min, max]` (the polygon is their hull).
    #[serde(
        default = "default_points",
        deserialize_with = "crate::world::exact::exact"
    )]
    pub points: [u32; 2],
    /// Minimum distance from the start and from the goal to every polygon, m.
    #[serde(default = "default_clearance")]
    pub clearance: f64,
    /// Minimum distance between two polygons, m (0 = they may touch or overlap,
    /// the paper's test). A polygon closer than this to an earlier one is drawn
    /// again; with 0 the generator draws exactly as before this field existed.
    #[serde(default)]
    pub min_gap: f64,
}

/// Largest [`RandomParams::count`] (large maps: `scenarios/large-map.toml`
/// draws 10,000 polygons in about 30 ms).
pub const MAX_COUNT: usize = 1_000_000;

/// Largest [`RandomParams::count`] with `min_gap > 0` (quadratic check).
pub const MAX_COUNT_WITH_GAP: usize = 1000;

fn default_kind() -> String {
    "random_polygons".into()
}
fn default_count() -> usize {
    8
}
fn default_area_min() -> [f64; 2] {
    [0.0, 0.0]
}
fn default_area_max() -> [f64; 2] {
    [10.0, 10.0]
}
fn default_radius() -> [f64; 2] {
    [0.3, 1.0]
}
fn default_points() -> [u32; 2] {
    [3, 8]
}
fn default_clearance() -> f64 {
    1.0
}

impl Default for RandomParams {
    fn default() -> Self {
        RandomParams {
            kind: default_kind(),
            count: default_count(),
            area_min: default_area_min(),
            area_max: default_area_max(),
            radius: default_radius(),
            points: default_points(),
            clearance: default_clearance(),
            min_gap: 0.0,
        }
    }
}

impl RandomParams {
    /// Checks the ranges; the error names the bad field.
    pub fn validate(&self) -> Result<(), SettingError> {
        if self.kind != "random_polygons"
            && !crate::world::families::FAMILIES.contains(&self.kind.as_str())
            && !crate::world::crowd::families::FAMILIES.contains(&self.kind.as_str())
        {
            return Err(SettingError::new(
                "kind",
                format!(
                    "unknown generator kind {:?} (\"random_polygons\" or a family: {}, {})",
                    self.kind,
                    crate::world::families::FAMILIES.join(", "),
                    crate::world::crowd::families::FAMILIES.join(", ")
                ),
            ));
        }
        let fin = |a: &[f64]| a.iter().all(|v| v.is_finite());
        if !(fin(&self.area_min)
            && fin(&self.area_max)
            && self.area_min[0] < self.area_max[0]
            && self.area_min[1] < self.area_max[1])
        {
            return Err(SettingError::new(
                "area_max",
                "area_min and area_max must be finite with area_min < area_max",
            ));
        }
        if !(fin(&self.radius) && self.radius[0] > 0.0 && self.radius[0] <= self.radius[1]) {
            return Err(SettingError::new(
                "radius",
                "must be [min, max] with 0 < min <= max",
            ));
        }
        if !(self.points[0] >= 3
            && self.points[0] <= self.points[1]
            && self.points[1] as usize <= MAX_VERTICES)
        {
            return Err(SettingError::new(
                "points",
                format!("must be [min, max] with 3 <= min <= max <= {MAX_VERTICES}"),
            ));
        }
        if !(self.clearance.is_finite() && self.clearance >= 0.0) {
            return Err(SettingError::new("clearance", "must be finite and >= 0"));
        }
        if !(self.min_gap.is_finite() && self.min_gap >= 0.0) {
            return Err(SettingError::new("min_gap", "must be finite and >= 0"));
        }
        if self.min_gap > 0.0 && self.count > MAX_COUNT_WITH_GAP {
            return Err(SettingError::new(
                "count",
                format!("must be <= {MAX_COUNT_WITH_GAP} with min_gap > 0"),
            ));
        }
        if self.count > MAX_COUNT {
            return Err(SettingError::new(
                "count",
                format!("must be <= {MAX_COUNT}"),
            ));
        }
        Ok(())
    }
}

/// Draws `params.count` random convex polygons with a ChaCha8 generator seeded by
/// `seed` (the same seed gives the same polygons on every platform). Each polygon
/// is the convex hull of `points` random points at random angles and radii in
/// `[0.5, 1] * r` around a uniform centre in the area, `r` uniform in `radius`;
/// a polygon closer than `clearance` to `start` or `goal` is drawn again.
pub fn random_obstacles(
    seed: u64,
    params: &RandomParams,
    start: Vector2<f64>,
    goal: Vector2<f64>,
) -> Result<Vec<Polygon>, String> {
    params.validate().map_err(|e| e.to_string())?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut unif = |lo: f64, hi: f64| {
        let u = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        lo + (hi - lo) * u
    };
    let mut out = Vec::with_capacity(params.count);
    let mut attempts = 0usize;
    while out.len() < params.count {
        attempts += 1;
        if attempts > 1000 * params.count.max(1) {
            return Err(format!(
                "could not place {} polygons clear of start and goal after {} attempts",
                params.count,
                attempts - 1
            ));
        }
        let cx = unif(params.area_min[0], params.area_max[0]);
        let cy = unif(params.area_min[1], params.area_max[1]);
        let r = unif(params.radius[0], params.radius[1]);
        let n = unif(
            f64::from(params.points[0]),
            f64::from(params.points[1]) + 1.0,
        )
        .floor()
        .min(f64::from(params.points[1])) as usize;
        let mut pts = Vec::with_capacity(n);
        for _ in 0..n {
            let a = unif(0.0, core::f64::consts::TAU);
            let rr = r * unif(0.5, 1.0);
            pts.push([cx + rr * a.cos(), cy + rr * a.sin()]);
        }
        let Ok(poly) = Polygon::hull(&pts) else {
            continue;
        };
        let clear = |p: Vector2<f64>| {
            closest_point_point_polygon(&p, &poly).signed_distance >= params.clearance
        };
        if clear(start)
            && clear(goal)
            && (params.min_gap <= 0.0
                || out
                    .iter()
                    .all(|o| polygon_distance(o, &poly) >= params.min_gap))
        {
            out.push(poly);
        }
    }
    Ok(out)
}

/// Distance between two convex polygons, m (0 when they touch or overlap): the
/// smallest vertex-to-polygon distance either way, or 0 if two edges cross.
pub fn polygon_distance(a: &Polygon, b: &Polygon) -> f64 {
    let cross = |o: Vector2<f64>, p: Vector2<f64>, q: Vector2<f64>| {
        (p.x - o.x) * (q.y - o.y) - (p.y - o.y) * (q.x - o.x)
    };
    let (va, vb) = (a.vertices(), b.vertices());
    for i in 0..va.len() {
        let (p1, p2) = (va[i], va[(i + 1) % va.len()]);
        for j in 0..vb.len() {
            let (q1, q2) = (vb[j], vb[(j + 1) % vb.len()]);
            let d1 = cross(p1, p2, q1);
            let d2 = cross(p1, p2, q2);
            let d3 = cross(q1, q2, p1);
            let d4 = cross(q1, q2, p2);
            if d1 * d2 <= 0.0 && d3 * d4 <= 0.0 {
                return 0.0;
            }
        }
    }
    let d = |v: &[Vector2<f64>], p: &Polygon| {
        v.iter()
            .map(|q| closest_point_point_polygon(q, p).signed_distance)
            .fold(f64::INFINITY, f64::min)
    };
    d(va, b).min(d(vb, a)).max(0.0)
}

/// Vertices of a regular polygon: vertex `i` at angle `rotation + 2 pi i / sides`
/// around `center`, at distance `radius` (m, rad).
pub fn regular_polygon(center: [f64; 2], radius: f64, sides: u32, rotation: f64) -> Vec<[f64; 2]> {
    (0..sides)
        .map(|i| {
            let a = rotation + core::f64::consts::TAU * f64::from(i) / f64::from(sides);
            [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
        })
        .collect()
}
