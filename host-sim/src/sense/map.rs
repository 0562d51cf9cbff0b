//! A map that remembers: a log-odds occupancy grid in the world frame W,
//! updated from each LiDAR scan and the sensor's pose, and the convex pieces
//! the controller gets from it.
//!
//! **Why a log-odds grid.** It is the representation of OctoMap (A. Hornung,
//! K. M. Wurm, M. Bennewitz, C. Stachniss, W. Burgard, "OctoMap: an efficient
//! probabilistic 3D mapping framework based on octrees", Autonomous Robots
//! 34, 2013) and of Nav2's voxel and obstacle layers, flattened to 2D: the
//! update of a cell is one addition (cheap), the memory is one `f32` per cell
//! of a fixed box (bounded, allocated once), a clamped cell changes its mind
//! after a few scans (a wall seen once and a ray that passed where it was
//! later are both kept as evidence, not overwritten), and the free and unknown
//! cells the planner and the safety rules need come for free.
//!
//! **Update** ([`OccupancyMap::update`]), per scan, as OctoMap's
//! `insertPointCloud`: every ray is traversed cell by cell from the sensor
//! (J. Amanatides and A. Woo, "A fast voxel traversal algorithm for ray
//! tracing", Eurographics 1987). A ray that hit gives a *hit* to the cell of
//! its hit point and a *miss* to every cell it passed through up to
//! `free_tolerance` (3 noise_sigma + free_margin, the LiDAR's own) short of its
//! hit; a ray that hit nothing gives a miss to every cell up to `range`. A cell
//! gets at most one update per scan, and a hit wins over a miss of the same
//! scan (a thin obstacle between two rays is not erased by its neighbours).
//! [`OccupancyMap::update_scan`] takes each ray's marked point and free
//! length instead: the simulator gives it those of the face fitted to each
//! ray's neighbours ([`crate::sense::faces`]), which let a ray clear up to
//! 1.6 cm (instead of 3.5 cm) in front of a wall.
//! Log-odds `L += log(p / (1 - p))` with `p = p_hit` or `p_miss`, clamped to
//! `[logit(clamp_min), logit(clamp_max)]` (OctoMap's clamping: a cell never
//! gets so sure that it cannot change within a few scans). With `decay > 0`
//! every known cell's log-odds shrinks by the factor `exp(-decay dt)` per
//! update (forgetting, for a world that changes; 0 = a static world).
//! The map's outermost ring of cells is never cleared (a hit still marks
//! it): nothing is known beyond the map's box, so free space seen up to the
//! box's edge ends in a frontier there, and a wall just beyond the box
//! (which the map cannot hold) is not walked into unseen.
//! A cell is *occupied* when `L > 0` (p > 0.5, OctoMap's occupancy
//! threshold), *free* when `L < 0`, *unknown* when never updated (or decayed
//! back to `|L| < 1e-3`).
//!
//! **Pieces** ([`OccupancyMap::pieces`]): the occupied cells within a radius
//! of the robot, and the *frontier* (unknown cells next to a free cell) within
//! `unknown_radius` of it, merged into axis-aligned rectangles of whole cells
//! (runs along x, stacked along y while a run of the next row has the same
//! ends). Each rectangle is exactly a union of such cells: a piece never
//! covers a cell seen free, and every occupied cell (and every near frontier
//! cell) is inside a piece. The frontier is what the robot has not seen next
//! to what it has: treated as an obstacle, it keeps the robot from stepping
//! into a shadow (an obstacle hidden behind another, a needle thinner than the
//! ray spacing) before it has seen into it.
//!
//! A piece is up to a cell (2.5 cm by default) larger than what it holds: the
//! price of pieces that never cover a cell seen free. (Shrinking each
//! rectangle to its cells' mean hit points, and convex hulls of those means
//! per group of cells, were tried: a wall then came in several pieces whose
//! ends gave the controller half-planes across a 0.7 m corridor, taken at
//! each piece's point nearest the robot, and the robot stopped in it.)

use ldcbf_controller::nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::world::Polygon;
use crate::world::grid::MAX_CELLS;
use crate::world::setting::SettingError;

/// Mapping settings: the `[lidar.map]` table. Probabilities in (0, 1).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MapParams {
    /// Cell side, m.
    pub resolution: f64,
    /// The map covers the bounding box of start and goal grown by this much on
    /// every side, m (cells outside it are never updated: unknown).
    pub padding: f64,
    /// Probability of a hit (OctoMap's default 0.7).
    pub p_hit: f64,
    /// Probability of a miss (OctoMap's default 0.4).
    pub p_miss: f64,
    /// Lower clamping probability (OctoMap's 0.1192).
    pub clamp_min: f64,
    /// Upper clamping probability (OctoMap's 0.971).
    pub clamp_max: f64,
    /// Forgetting rate, 1/s: known cells' log-odds shrink by `exp(-decay dt)`
    /// per update (0 = a static world, the default).
    pub decay: f64,
    /// Unknown cells next to a free cell within this distance of the robot
    /// are obstacles for the controller, m (0 = never).
    pub unknown_radius: f64,
    /// The capture-step speed limit (`crate::sim::capture`): each cycle's
    /// speed cap lets the robot stop inside the space seen free along its
    /// planned way (default false: docs/safety.md gives its measured cost).
    pub capture_speed_limit: bool,
}

impl Default for MapParams {
    fn default() -> Self {
        MapParams {
            resolution: 0.025,
            padding: 3.0,
            p_hit: 0.7,
            p_miss: 0.4,
            clamp_min: 0.1192,
            clamp_max: 0.971,
            decay: 0.0,
            unknown_radius: 1.0,
            capture_speed_limit: false,
        }
    }
}

impl MapParams {
    /// Checks every field; the error names the bad one (as `map.FIELD`).
    pub fn validate(&self) -> Result<(), SettingError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let prob = |v: f64| v > 0.0 && v < 1.0;
        if !(pos(self.resolution) && self.resolution <= 1.0) {
            return Err(SettingError::new("map.resolution", "must be in (0, 1] m"));
        }
        if !(self.padding.is_finite() && (0.0..=100.0).contains(&self.padding)) {
            return Err(SettingError::new("map.padding", "must be in [0, 100] m"));
        }
        if !(prob(self.p_hit) && self.p_hit > 0.5) {
            return Err(SettingError::new("map.p_hit", "must be in (0.5, 1)"));
        }
        if !(prob(self.p_miss) && self.p_miss < 0.5) {
            return Err(SettingError::new("map.p_miss", "must be in (0, 0.5)"));
        }
        if !(prob(self.clamp_min) && self.clamp_min < 0.5) {
            return Err(SettingError::new("map.clamp_min", "must be in (0, 0.5)"));
        }
        if !(prob(self.clamp_max) && self.clamp_max > 0.5) {
            return Err(SettingError::new("map.clamp_max", "must be in (0.5, 1)"));
        }
        if !(self.decay.is_finite() && self.decay >= 0.0) {
            return Err(SettingError::new("map.decay", "must be finite and >= 0"));
        }
        if !(self.unknown_radius.is_finite() && self.unknown_radius >= 0.0) {
            return Err(SettingError::new(
                "map.unknown_radius",
                "must be finite and >= 0",
            ));
        }
        Ok(())
    }
}

/// What the map says about a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellState {
    /// Never seen (or forgotten).
    Unknown,
    /// Seen free (log-odds < 0).
    Free,
    /// Seen occupied (log-odds > 0).
    Occupied,
}

/// Log-odds `ln(p / (1 - p))`.
fn logit(p: f64) -> f32 {
    (p / (1.0 - p)).ln() as f32
}

/// |log-odds| below this is unknown.
const UNKNOWN_EPS: f32 = 1e-3;

/// A log-odds occupancy grid over a fixed box (module docs).
#[derive(Clone, Debug)]
pub struct OccupancyMap {
    /// World position of the lower-left corner of cell `(0, 0)`, m.
    pub origin: Vector2<f64>,
    /// Cell side, m.
    pub resolution: f64,
    /// Cells along x.
    pub width: usize,
    /// Cells along y.
    pub height: usize,
    log_odds: Vec<f32>,
    /// Scan number of each cell's last update (one update per scan).
    stamp: Vec<u32>,
    scans: u32,
    hit: f32,
    miss: f32,
    lo: f32,
    hi: f32,
    params: MapParams,
}

impl OccupancyMap {
    /// An all-unknown map over the box `[lo, hi]` (m) grown by
    /// `params.padding`; fails on invalid params or more than
    /// [`MAX_CELLS`] cells.
    pub fn new(params: MapParams, lo: Vector2<f64>, hi: Vector2<f64>) -> Result<Self, String> {
        params.validate().map_err(|e| e.to_string())?;
        let pad = Vector2::repeat(params.padding);
        let (lo, hi) = (lo.inf(&hi) - pad, lo.sup(&hi) + pad);
        let r = params.resolution;
        let w = ((hi.x - lo.x) / r).ceil().max(1.0);
        let h = ((hi.y - lo.y) / r).ceil().max(1.0);
        if w * h > MAX_CELLS as f64 {
            return Err(format!(
                "map: {} cells (more than {MAX_CELLS}): raise map.resolution or lower map.padding",
                w * h
            ));
        }
        let (width, height) = (w as usize, h as usize);
        Ok(OccupancyMap {
            origin: lo,
            resolution: r,
            width,
            height,
            log_odds: vec![0.0; width * height],
            stamp: vec![0; width * height],
            scans: 0,
            hit: logit(params.p_hit),
            miss: logit(params.p_miss),
            lo: logit(params.clamp_min),
            hi: logit(params.clamp_max),
            params,
        })
    }

    /// The settings.
    pub fn params(&self) -> &MapParams {
        &self.params
    }

    /// The cell containing `p` (m), if inside the map.
    pub fn cell_of(&self, p: Vector2<f64>) -> Option<(usize, usize)> {
        let i = ((p.x - self.origin.x) / self.resolution).floor();
        let j = ((p.y - self.origin.y) / self.resolution).floor();
        (i >= 0.0 && j >= 0.0 && i < self.width as f64 && j < self.height as f64)
            .then_some((i as usize, j as usize))
    }

    /// Centre of cell `(i, j)`, m.
    pub fn centre(&self, i: usize, j: usize) -> Vector2<f64> {
        self.origin + Vector2::new(i as f64 + 0.5, j as f64 + 0.5) * self.resolution
    }

    /// The log-odds of cell `(i, j)`.
    pub fn log_odds(&self, i: usize, j: usize) -> f32 {
        self.log_odds[j * self.width + i]
    }

    /// Whether cell index `k` (`j * width + i`) is in the map's outermost
    /// ring, which no ray clears (module docs).
    fn on_edge(&self, k: usize) -> bool {
        let (i, j) = (k % self.width, k / self.width);
        i == 0 || j == 0 || i + 1 >= self.width || j + 1 >= self.height
    }

    /// The state of cell `(i, j)` (module docs).
    pub fn state(&self, i: usize, j: usize) -> CellState {
        let l = self.log_odds[j * self.width + i];
        if l.abs() < UNKNOWN_EPS {
            CellState::Unknown
        } else if l > 0.0 {
            CellState::Occupied
        } else {
            CellState::Free
        }
    }

    /// The state of the cell containing `p` ([`CellState::Unknown`] outside).
    pub fn state_at(&self, p: Vector2<f64>) -> CellState {
        self.cell_of(p)
            .map_or(CellState::Unknown, |(i, j)| self.state(i, j))
    }

    /// Every cell's state, row by row (`j * width + i`).
    pub fn states(&self) -> Vec<CellState> {
        (0..self.height)
            .flat_map(|j| (0..self.width).map(move |i| (i, j)))
            .map(|(i, j)| self.state(i, j))
            .collect()
    }

    /// Adds one scan taken from `origin` (m) with the sensor's zero angle along
    /// `heading` (rad): `rays[k]` is ray `k`'s hit point or `None` (as
    /// [`crate::sense::Lidar::scan_rays`] returns them), `range` the LiDAR's
    /// range and `tol` its free-space tolerance (m), `dt` the time since the
    /// last update (s, for `decay`).
    pub fn update(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        rays: &[Option<Vector2<f64>>],
        range: f64,
        tol: f64,
        dt: f64,
    ) {
        self.update_keeping_out(origin, heading, rays, range, tol, dt, &[]);
    }

    /// [`OccupancyMap::update`] with the hits of the rays flagged in
    /// `kept_out` (one flag per ray; missing flags are `false`) left out:
    /// those rays still clear the cells in front of their hits, but give no
    /// hit (a tracked person, [`crate::sense::movers`], is not a wall).
    #[allow(clippy::too_many_arguments)]
    pub fn update_keeping_out(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        rays: &[Option<Vector2<f64>>],
        range: f64,
        tol: f64,
        dt: f64,
        kept_out: &[bool],
    ) {
        let free: Vec<f64> = rays
            .iter()
            .map(|p| p.map_or(range, |p| (p - origin).norm() - tol))
            .collect();
        self.update_scan(origin, heading, rays, &free, dt, kept_out);
    }

    /// [`OccupancyMap::update_keeping_out`] with each ray's free length
    /// given: ray `k` gives a miss to every cell it passes through up to
    /// `free[k]` (m) from `origin` (a missing length: none), e.g. from
    /// [`crate::sense::faces::free_lengths`].
    pub fn update_scan(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        rays: &[Option<Vector2<f64>>],
        free: &[f64],
        dt: f64,
        kept_out: &[bool],
    ) {
        if self.params.decay > 0.0 && dt > 0.0 {
            let f = (-self.params.decay * dt).exp() as f32;
            for l in &mut self.log_odds {
                *l *= f;
            }
        }
        self.scans = self.scans.wrapping_add(1).max(1);
        let scan = self.scans;
        // Hits first: they win over this scan's misses.
        for (k, p) in rays.iter().enumerate() {
            let Some(p) = p else { continue };
            if kept_out.get(k).copied().unwrap_or(false) {
                continue;
            }
            if let Some((i, j)) = self.cell_of(*p) {
                let k = j * self.width + i;
                if self.stamp[k] != scan {
                    self.stamp[k] = scan;
                    self.log_odds[k] = (self.log_odds[k] + self.hit).clamp(self.lo, self.hi);
                }
            }
        }
        let n = rays.len();
        for k in 0..n {
            let d = crate::sense::ray_direction(heading, k, n);
            let len = free.get(k).copied().unwrap_or(0.0);
            if len > 0.0 {
                self.traverse(origin, d, len, |map, c| {
                    if map.stamp[c] != scan && !map.on_edge(c) {
                        map.stamp[c] = scan;
                        map.log_odds[c] = (map.log_odds[c] + map.miss).clamp(map.lo, map.hi);
                    }
                });
            }
        }
    }

    /// The column range `(i0, i1)` and row range `(j0, j1)` (inclusive) of
    /// the cells that overlap the box from `lo` to `hi` (world frame, m),
    /// clamped to the map.
    pub fn cell_range(
        &self,
        lo: Vector2<f64>,
        hi: Vector2<f64>,
    ) -> ((usize, usize), (usize, usize)) {
        let r = self.resolution;
        let idx =
            |x: f64, o: f64, n: usize| (((x - o) / r).floor().clamp(0.0, n as f64 - 1.0)) as usize;
        (
            (
                idx(lo.x, self.origin.x, self.width),
                idx(hi.x, self.origin.x, self.width),
            ),
            (
                idx(lo.y, self.origin.y, self.height),
                idx(hi.y, self.origin.y, self.height),
            ),
        )
    }

    /// Clears the occupied cells whose centre is within `margin` (m) of
    /// `poly` (world frame): their log-odds become one miss's (free, not
    /// sure). For the cells of something that moves and was mapped before it
    /// was known to ([`crate::sense::movers`]: a person at the edge of the
    /// range, or seen in one cluster with a wall).
    pub fn clear_polygon(&mut self, poly: &Polygon, margin: f64) {
        let (lo, hi) = crate::world::obstacle_index::bounding_box(poly);
        let (lo, hi) = (Vector2::from(lo), Vector2::from(hi));
        let m = Vector2::repeat(margin);
        let (lo, hi) = (lo - m, hi + m);
        if hi.x < self.origin.x || hi.y < self.origin.y {
            return;
        }
        let ((i0, i1), (j0, j1)) = self.cell_range(lo, hi);
        for j in j0..=j1 {
            for i in i0..=i1 {
                let k = j * self.width + i;
                if self.log_odds[k] > 0.0
                    && !self.on_edge(k)
                    && ldcbf_controller::closest_point_point_polygon(&self.centre(i, j), poly)
                        .signed_distance
                        <= margin
                {
                    self.log_odds[k] = self.miss;
                }
            }
        }
    }

    /// Calls `f` with the index of every cell the segment from `o` along the
    /// unit direction `d` to length `len` (m) passes through, in order, inside
    /// the map (Amanatides-Woo traversal; the segment is clipped to the map).
    pub fn traverse(
        &mut self,
        o: Vector2<f64>,
        d: Vector2<f64>,
        len: f64,
        mut f: impl FnMut(&mut Self, usize),
    ) {
        let r = self.resolution;
        let size = Vector2::new(self.width as f64, self.height as f64) * r;
        // Clip [0, len] to the map box (slab test).
        let (mut t0, mut t1) = (0.0f64, len);
        for a in 0..2 {
            let (p, v, hi) = (o[a] - self.origin[a], d[a], size[a]);
            if v.abs() < 1e-15 {
                if p < 0.0 || p >= hi {
                    return;
                }
            } else {
                let (ta, tb) = ((0.0 - p) / v, (hi - p) / v);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0 >= t1 {
            return;
        }
        let start = o + d * t0 - self.origin;
        let clampi = |x: f64, n: usize| ((x / r).floor().max(0.0) as usize).min(n - 1);
        let (mut i, mut j) = (clampi(start.x, self.width), clampi(start.y, self.height));
        let step = |v: f64| if v > 0.0 { 1isize } else { -1 };
        let (si, sj) = (step(d.x), step(d.y));
        let next = |c: usize, s: isize, v: f64, p: f64| {
            if v.abs() < 1e-15 {
                f64::INFINITY
            } else {
                let b = (c as f64 + if s > 0 { 1.0 } else { 0.0 }) * r;
                t0 + (b - p) / v
            }
        };
        let mut tx = next(i, si, d.x, start.x);
        let mut ty = next(j, sj, d.y, start.y);
        let dtx = if d.x.abs() < 1e-15 {
            f64::INFINITY
        } else {
            r / d.x.abs()
        };
        let dty = if d.y.abs() < 1e-15 {
            f64::INFINITY
        } else {
            r / d.y.abs()
        };
        // At most one cell per crossing of a grid line, plus the first.
        let max_cells = self.width + self.height + 2;
        for _ in 0..max_cells {
            f(self, j * self.width + i);
            if tx < ty {
                if tx >= t1 {
                    return;
                }
                tx += dtx;
                match i.checked_add_signed(si) {
                    Some(n) if n < self.width => i = n,
                    _ => return,
                }
            } else {
                if ty >= t1 {
                    return;
                }
                ty += dty;
                match j.checked_add_signed(sj) {
                    Some(n) if n < self.height => j = n,
                    _ => return,
                }
            }
        }
    }

    /// Whether cell `(i, j)` is unknown with a free 4-neighbour.
    fn is_frontier(&self, i: usize, j: usize) -> bool {
        self.state(i, j) == CellState::Unknown
            && [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(di, dj)| {
                match (i.checked_add_signed(di), j.checked_add_signed(dj)) {
                    (Some(a), Some(b)) if a < self.width && b < self.height => {
                        self.state(a, b) == CellState::Free
                    }
                    _ => false,
                }
            })
    }

    /// The controller's obstacles (module docs): the occupied cells whose
    /// centre is within `radius` (m) of `at`, and the frontier cells within
    /// `unknown_radius` of `at`, as rectangles of whole cells, world frame.
    pub fn pieces(&self, at: Vector2<f64>, radius: f64) -> Vec<Polygon> {
        let r = self.resolution;
        let ur = self.params.unknown_radius;
        let reach = radius.max(ur) + r;
        let rng = |c: f64, o: f64, n: usize| {
            ((((c - o) / r).floor()).clamp(0.0, n as f64 - 1.0)) as usize
        };
        let (i0, i1) = (
            rng(at.x - reach, self.origin.x, self.width),
            rng(at.x + reach, self.origin.x, self.width),
        );
        let (j0, j1) = (
            rng(at.y - reach, self.origin.y, self.height),
            rng(at.y + reach, self.origin.y, self.height),
        );
        let wanted = |i: usize, j: usize| {
            let dd = (self.centre(i, j) - at).norm();
            match self.state(i, j) {
                CellState::Occupied => dd <= radius,
                CellState::Unknown => dd <= ur && self.is_frontier(i, j),
                CellState::Free => false,
            }
        };
        let mut rects = Vec::new();
        // Open rectangles: (i_first, i_last, j_first), extended row by row.
        let mut open: Vec<(usize, usize, usize)> = Vec::new();
        for j in j0..=j1 + 1 {
            let mut runs = Vec::new();
            if j <= j1 {
                let mut i = i0;
                while i <= i1 {
                    if wanted(i, j) {
                        let a = i;
                        while i < i1 && wanted(i + 1, j) {
                            i += 1;
                        }
                        runs.push((a, i));
                    }
                    i += 1;
                }
            }
            let mut still = Vec::new();
            for (a, b, jf) in open.drain(..) {
                if let Some(k) = runs.iter().position(|&(x, y)| (x, y) == (a, b)) {
                    runs.swap_remove(k);
                    still.push((a, b, jf));
                } else {
                    rects.push((a, b, jf, j - 1));
                }
            }
            still.extend(runs.into_iter().map(|(a, b)| (a, b, j)));
            open = still;
        }
        rects
            .into_iter()
            .filter_map(|(a, b, ja, jb)| {
                let p0 = self.origin + Vector2::new(a as f64, ja as f64) * r;
                let p1 = self.origin + Vector2::new((b + 1) as f64, (jb + 1) as f64) * r;
                Polygon::new(&[[p0.x, p0.y], [p1.x, p0.y], [p1.x, p1.y], [p0.x, p1.y]]).ok()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sense::{Lidar, LidarParams, free_tolerance};
    use crate::world::square;

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    fn map(params: MapParams) -> OccupancyMap {
        OccupancyMap::new(params, v(-2.0, -2.0), v(2.0, 2.0)).unwrap()
    }

    #[test]
    fn traversal_visits_every_cell_a_segment_crosses_in_order() {
        let mut m = map(MapParams {
            resolution: 0.5,
            padding: 0.0,
            ..MapParams::default()
        });
        let mut seen = Vec::new();
        let d = v(1.0, 0.5).normalize();
        m.traverse(v(-1.9, -1.9), d, 2.0, |m, k| {
            seen.push((k % m.width, k / m.width))
        });
        // From cell (0, 0) along slope 1/2: the cells crossed, 4-connected.
        assert_eq!(seen[0], (0, 0));
        for w in seen.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert_eq!(a.0.abs_diff(b.0) + a.1.abs_diff(b.1), 1, "{seen:?}");
        }
        let end = v(-1.9, -1.9) + d * 2.0;
        assert_eq!(*seen.last().unwrap(), m.cell_of(end).unwrap(), "{seen:?}");
        // A segment starting outside the map is clipped to it.
        let mut n = 0;
        m.traverse(v(-3.0, 0.1), v(1.0, 0.0), 10.0, |_, _| n += 1);
        assert_eq!(n, m.width);
    }

    /// Rays that run off the map clear up to its outermost ring, which stays
    /// unknown: a frontier piece stands at the box's edge (where a wall
    /// beyond the box would be), and none covers a cell seen free.
    #[test]
    fn the_map_ends_in_a_frontier_at_its_edge() {
        let mut m = map(MapParams {
            resolution: 0.1,
            padding: 0.0,
            unknown_radius: 1.0,
            ..MapParams::default()
        });
        // At (1.45, 0.05), 0.55 m from the map's edge x = 2; 8 rays, none hits.
        let o = v(1.45, 0.05);
        m.update(o, 0.0, &[None; 8], 3.0, 0.03, 0.0);
        let last = m.width - 1;
        let (_, j) = m.cell_of(o).unwrap();
        assert_eq!(m.state(last, j), CellState::Unknown);
        assert_eq!(m.state(last - 1, j), CellState::Free);
        let pieces = m.pieces(o, 1.0);
        let edge = m.centre(last, j);
        assert!(
            pieces.iter().any(|p| {
                ldcbf_controller::closest_point_point_polygon(&edge, p).signed_distance <= 0.0
            }),
            "no piece at the edge: {pieces:?}"
        );
        let inner = m.centre(last - 1, j);
        assert!(pieces.iter().all(|p| {
            ldcbf_controller::closest_point_point_polygon(&inner, p).signed_distance > 0.0
        }));
    }

    #[test]
    fn a_hit_marks_its_cell_and_the_ray_clears_the_cells_before_it() {
        let p = MapParams {
            resolution: 0.1,
            ..MapParams::default()
        };
        let mut m = map(p);
        let o = v(0.05, 0.05);
        // Ray 0 of 4 (along +x) hits at x = 1.05; the others miss within 1 m.
        let rays = [Some(v(1.05, 0.05)), None, None, None];
        m.update(o, 0.0, &rays, 1.0, 0.03, 0.0);
        assert_eq!(m.state_at(v(1.05, 0.05)), CellState::Occupied);
        for x in [0.05, 0.35, 0.95] {
            assert_eq!(m.state_at(v(x, 0.05)), CellState::Free, "x = {x}");
        }
        assert_eq!(
            m.state_at(v(0.05, 0.95)),
            CellState::Free,
            "a missed ray clears to its range"
        );
        assert_eq!(
            m.state_at(v(0.05, 1.25)),
            CellState::Unknown,
            "beyond the range"
        );
        assert_eq!(
            m.state_at(v(1.55, 0.05)),
            CellState::Unknown,
            "behind the hit"
        );
        // The obstacle moved away: rays now pass through its cell, which turns
        // free after a few scans (clamped: never more than it takes).
        let rays = [Some(v(1.85, 0.05)), None, None, None];
        let mut scans = 0;
        while m.state_at(v(1.05, 0.05)) == CellState::Occupied {
            m.update(o, 0.0, &rays, 2.0, 0.03, 0.0);
            scans += 1;
            assert!(scans < 10);
        }
        assert!(scans >= 2, "one miss does not erase a hit ({scans})");
        // Clamping: after many more hits it still clears in a bounded number.
        for _ in 0..100 {
            m.update(
                o,
                0.0,
                &[Some(v(1.05, 0.05)), None, None, None],
                1.0,
                0.03,
                0.0,
            );
        }
        let (i, j) = m.cell_of(v(1.05, 0.05)).unwrap();
        assert!(m.log_odds(i, j) <= logit(0.971) + 1e-6);
        let mut scans = 0;
        while m.state_at(v(1.05, 0.05)) == CellState::Occupied {
            m.update(o, 0.0, &rays, 2.0, 0.03, 0.0);
            scans += 1;
        }
        assert!(scans <= 9, "{scans}");
    }

    #[test]
    fn a_hit_wins_over_a_miss_of_the_same_scan() {
        let mut m = map(MapParams {
            resolution: 0.2,
            ..MapParams::default()
        });
        // Two rays 1 degree apart: one hits at 1.1 m, the other passes
        // through the same cell to 1.9 m.
        let o = v(0.0, 0.0);
        let d0 = crate::sense::ray_direction(0.0, 0, 360);
        let d1 = crate::sense::ray_direction(0.0, 1, 360);
        let mut rays = vec![None; 360];
        rays[0] = Some(o + d0 * 1.1);
        rays[1] = Some(o + d1 * 1.9);
        m.update(o, 0.0, &rays, 3.0, 0.0, 0.0);
        assert_eq!(m.state_at(o + d0 * 1.1), CellState::Occupied);
    }

    #[test]
    fn pieces_cover_every_occupied_cell_and_no_free_one() {
        let lidar_params = LidarParams::default();
        let mut lidar = Lidar::new(lidar_params.clone(), 7).unwrap();
        let obstacles = [square([1.0, 0.3], 0.2), square([-0.8, -0.9], 0.3)];
        let mut m = map(MapParams {
            resolution: 0.05,
            padding: 0.5,
            ..MapParams::default()
        });
        let tol = free_tolerance(&lidar_params);
        for k in 0..5 {
            let o = v(-0.5 + 0.1 * f64::from(k), 0.2);
            let rays = lidar.scan_rays(o, 0.0, &obstacles);
            m.update(o, 0.0, &rays, lidar_params.range, tol, 0.05);
        }
        let at = v(0.0, 0.2);
        let pieces = m.pieces(at, 3.0);
        assert!(!pieces.is_empty());
        let mut occupied = 0;
        for j in 0..m.height {
            for i in 0..m.width {
                let c = m.centre(i, j);
                let inside = pieces.iter().any(|p| p.contains(&c));
                match m.state(i, j) {
                    CellState::Occupied => {
                        occupied += 1;
                        assert!(inside, "occupied cell {i} {j} left out");
                    }
                    CellState::Free => assert!(!inside, "free cell {i} {j} covered"),
                    CellState::Unknown => {
                        if inside {
                            assert!(m.is_frontier(i, j) && (c - at).norm() <= 1.0);
                        }
                    }
                }
            }
        }
        assert!(occupied > 10);
        // Both obstacles are seen: occupied cells on their faces.
        for ob in &obstacles {
            let near = (0..m.height)
                .flat_map(|j| (0..m.width).map(move |i| (i, j)))
                .filter(|&(i, j)| m.state(i, j) == CellState::Occupied)
                .any(|(i, j)| {
                    ldcbf_controller::closest_point_point_polygon(&m.centre(i, j), ob)
                        .signed_distance
                        .abs()
                        < 0.03
                });
            assert!(near, "{:?}", ob.vertices());
        }
        // No piece contains the sensor.
        assert!(pieces.iter().all(|p| !p.contains(&at)));
    }

    #[test]
    fn decay_forgets_and_bad_settings_name_their_field() {
        let mut m = map(MapParams {
            decay: 1.0,
            ..MapParams::default()
        });
        m.update(v(0.0, 0.0), 0.0, &[Some(v(0.5, 0.0))], 1.0, 0.0, 0.0);
        assert_eq!(m.state_at(v(0.5, 0.0)), CellState::Occupied);
        m.update(v(0.0, 0.0), 0.0, &[], 1.0, 0.0, 20.0);
        assert_eq!(m.state_at(v(0.5, 0.0)), CellState::Unknown);
        let bad = MapParams {
            p_hit: 0.4,
            ..MapParams::default()
        };
        assert_eq!(bad.validate().unwrap_err().field, "map.p_hit");
        let huge = MapParams {
            resolution: 0.001,
            padding: 100.0,
            ..MapParams::default()
        };
        assert!(OccupancyMap::new(huge, v(0.0, 0.0), v(1.0, 1.0)).is_err());
    }
}
