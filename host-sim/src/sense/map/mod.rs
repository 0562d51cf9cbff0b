//! A map that remembers: a log-odds occupancy grid in the world frame W,
//! updated from each LiDAR scan and the sensor's pose, and the convex pieces
//! the controller gets from it.
//!
//! **Why a log-odds grid.** It is the representation of OctoMap (A. Hornung,
//! K. M. Wurm, M. Bennewitz, C. Stachniss, W. Burgard, "OctoMap: an efficient
//! probabilistic 3D mapping framework based on octrees", Autonomous Robots
//! 34, 2013) and of Nav2's voxel and obstacle layers, flattened to 2D: the
//! update of a cell is one addition (cheap), the memory is one `f32` (and a
//! `u32` scan stamp) per cell of a box (bounded by `max_cells`, re-allocated
//! only when it grows), a clamped cell changes its mind
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
//! With `hit_overrides_misses` (the default) a hit also wins over the misses
//! of earlier scans: the cell of a hit is occupied after the scan (its
//! log-odds at least one hit's) however often rays passed through it before.
//! A cell is 2.5 cm wide and a ray proves free only its own line through
//! it: a needle's tip or a thin wall seen at a grazing angle fills a sliver
//! of its cells, rays beside it clear them scan after scan, and the hits,
//! which slide along the object as the robot walks, each land in a cell
//! with many misses, which one hit (`+logit(p_hit)` against a clamped
//! `logit(clamp_min)`) does not turn occupied: without the rule the needle
//! of `crowded` seed 174 is hit in nearly every scan and stays free in the
//! map until the body touches it. Nav2's obstacle layer does the same (the
//! clearing observations are ray-traced first, then every point of the
//! marking observations sets its cell lethal). Later misses clear the cell
//! as before (three scans from one hit). The exception is the noise band:
//! a hit with an occupied cell within `hit_noise_band` of it counts as an
//! ordinary hit (it may be a noise hit of that obstacle's face; without the
//! band the noise hits of grazing rays in front of a corridor's walls turn
//! occupied and narrow it).
//! [`OccupancyMap::update_scan`] takes each ray's marked point and free
//! length instead: the simulator gives it those of the face fitted to each
//! ray's neighbours ([`crate::sense::faces`]), which let a ray clear up to
//! 1.6 cm (instead of 3.5 cm) in front of a wall.
//! Log-odds `L += log(p / (1 - p))` with `p = p_hit` or `p_miss`, clamped to
//! `[logit(clamp_min), logit(clamp_max)]` (OctoMap's clamping: a cell never
//! gets so sure that it cannot change within a few scans). With `decay > 0`
//! every known cell's log-odds shrinks by the factor `exp(-decay dt)` per
//! update (forgetting, for a world that changes; 0 = a static world).
//!
//! **A map that grows with the robot** ([`OccupancyMap::grow_to_cover`]).
//! The first box is the bounding box of start and goal grown by
//! `padding`; before each scan, when the scan's reach (the farthest hit or
//! free length from the sensor, plus a cell) leaves the box's inner cells,
//! the box grows by whole cells on the sides that need it (plus
//! `GROW_SLACK`, 2 m), re-allocated with every cell's log-odds copied to the
//! same world position, as Nav2's static layer grows with its map (a rolling
//! window around the robot, the other choice, forgets the walls it leaves
//! behind, which the planner needs to not walk back into a dead end). The
//! map's outermost ring of cells is never cleared (a hit still marks it):
//! nothing is known beyond the box, so free space seen up to the box's edge
//! ends in a frontier there, and a wall just beyond the box (which the map
//! cannot hold) is not walked into unseen. With the box grown to every
//! scan's reach no ray reaches that ring: it holds only space no ray has
//! reached. The map holds at most `max_cells` cells (8 bytes each); a
//! growth past that is refused and the map keeps its box, whose edge then
//! holds the robot in as a box that never grows (`grow = false`) does.
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

mod grow;
mod params;
mod pieces;
mod traverse;
mod update;

#[cfg(test)]
mod tests;

use ldcbf_controller::nalgebra::Vector2;

pub use grow::Growth;
pub use params::MapParams;

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

/// The state of a cell of log-odds `l`.
fn state_of(l: f32) -> CellState {
    if l.abs() < UNKNOWN_EPS {
        CellState::Unknown
    } else if l > 0.0 {
        CellState::Occupied
    } else {
        CellState::Free
    }
}

/// A log-odds occupancy grid over a box that grows with the scans (module
/// docs).
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
    /// Times the box grew.
    grows: usize,
    /// Scans whose reach the box could not grow to ([`MapParams::max_cells`]).
    refused: usize,
}

impl OccupancyMap {
    /// An all-unknown map over the box `[lo, hi]` (m) grown by
    /// `params.padding`; fails on invalid params or more than
    /// `params.max_cells` cells.
    pub fn new(params: MapParams, lo: Vector2<f64>, hi: Vector2<f64>) -> Result<Self, String> {
        params.validate().map_err(|e| e.to_string())?;
        let pad = Vector2::repeat(params.padding);
        let (lo, hi) = (lo.inf(&hi) - pad, lo.sup(&hi) + pad);
        let r = params.resolution;
        let w = ((hi.x - lo.x) / r).ceil().max(1.0);
        let h = ((hi.y - lo.y) / r).ceil().max(1.0);
        if w * h > params.max_cells as f64 {
            return Err(format!(
                "map: {} cells (more than map.max_cells = {}): raise map.resolution or lower map.padding",
                w * h,
                params.max_cells
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
            grows: 0,
            refused: 0,
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
        state_of(self.log_odds[j * self.width + i])
    }

    /// The state of the cell containing `p` ([`CellState::Unknown`] outside).
    pub fn state_at(&self, p: Vector2<f64>) -> CellState {
        self.cell_of(p)
            .map_or(CellState::Unknown, |(i, j)| self.state(i, j))
    }

    /// Every cell's state, row by row (`j * width + i`).
    pub fn states(&self) -> Vec<CellState> {
        self.log_odds.iter().map(|&l| state_of(l)).collect()
    }

    /// Whether each cell is [`CellState::Occupied`], row by row (`j * width
    /// + i`).
    pub fn occupied(&self) -> Vec<bool> {
        self.flagged(CellState::Occupied)
    }

    /// Every cell's `(occupied, unknown)` flags, row by row (`j * width +
    /// i`): the planner's view of [`OccupancyMap::states`].
    pub fn flags(&self) -> (Vec<bool>, Vec<bool>) {
        (self.occupied(), self.flagged(CellState::Unknown))
    }

    /// Whether each cell is in `state`, row by row.
    fn flagged(&self, state: CellState) -> Vec<bool> {
        self.log_odds
            .iter()
            .map(|&l| state_of(l) == state)
            .collect()
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
}
