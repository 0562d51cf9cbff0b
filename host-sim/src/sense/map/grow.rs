//! A map that grows with the robot: when a scan's reach leaves the box, the
//! box grows by whole cells (re-allocated, every cell's log-odds and stamp
//! copied to the same world position), so that no ray ever reaches the
//! outermost ring (module docs of [`super`]).

use ldcbf_controller::nalgebra::Vector2;

use super::OccupancyMap;

/// Extra room a growing side gets beyond what the scan needs, m: the robot
/// walks about this far before the box grows again on that side.
pub const GROW_SLACK: f64 = 2.0;

/// What [`OccupancyMap::grow_to_cover`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Growth {
    /// The box's inner cells already covered the asked box.
    Covered,
    /// The box grew.
    Grown,
    /// Growing would pass [`super::MapParams::max_cells`]: the box is kept.
    AtBound,
}

/// Cells to add below and above along one axis so that the inner cells
/// (`1..n - 1`) of an axis of `n` cells from `origin` (m, cell side `r`)
/// cover `[lo, hi]` (m), each side that needs any given `slack` more cells.
fn needed(origin: f64, r: f64, n: usize, lo: f64, hi: f64, slack: usize) -> (usize, usize) {
    let a = ((lo - origin) / r).floor();
    let b = ((hi - origin) / r).floor();
    let below = (1.0 - a).max(0.0) as usize;
    let above = (b - (n as f64 - 2.0)).max(0.0) as usize;
    let add = |c: usize| if c > 0 { c + slack } else { 0 };
    (add(below), add(above))
}

impl OccupancyMap {
    /// Grows the box so that its inner cells (all but the outermost ring)
    /// cover the box from `lo` to `hi` (world frame, m), each side that grows
    /// by `GROW_SLACK` (2 m) more (or, when that would pass `max_cells`, by
    /// exactly what is needed). Every cell keeps its state at its world
    /// position; new cells are unknown. When even the exact growth would pass
    /// `max_cells` the map is left as it is ([`Growth::AtBound`]: rays then
    /// stop at the box's edge, where the frontier holds the robot in, as in a
    /// box that never grows).
    pub fn grow_to_cover(&mut self, lo: Vector2<f64>, hi: Vector2<f64>) -> Growth {
        if !(lo.iter().chain(hi.iter()).all(|v| v.is_finite())) {
            return Growth::Covered;
        }
        let r = self.resolution;
        let slack = (GROW_SLACK / r).ceil() as usize;
        let plan = |s: usize| {
            let (l, rt) = needed(self.origin.x, r, self.width, lo.x, hi.x, s);
            let (b, t) = needed(self.origin.y, r, self.height, lo.y, hi.y, s);
            let (w, h) = (self.width + l + rt, self.height + b + t);
            (l, b, w, h)
        };
        let fits = |(_, _, w, h): (usize, usize, usize, usize)| {
            w.checked_mul(h).is_some_and(|c| c <= self.params.max_cells)
        };
        let exact = plan(0);
        if (exact.2, exact.3) == (self.width, self.height) {
            return Growth::Covered;
        }
        let (left, bottom, w, h) = if fits(plan(slack)) {
            plan(slack)
        } else if fits(exact) {
            exact
        } else {
            self.refused += 1;
            return Growth::AtBound;
        };
        let mut log_odds = vec![0.0f32; w * h];
        let mut stamp = vec![0u32; w * h];
        for j in 0..self.height {
            let (src, dst) = (j * self.width, (j + bottom) * w + left);
            log_odds[dst..dst + self.width].copy_from_slice(&self.log_odds[src..src + self.width]);
            stamp[dst..dst + self.width].copy_from_slice(&self.stamp[src..src + self.width]);
        }
        self.origin -= Vector2::new(left as f64, bottom as f64) * r;
        (self.width, self.height) = (w, h);
        self.log_odds = log_odds;
        self.stamp = stamp;
        self.grows += 1;
        Growth::Grown
    }

    /// Times the box grew.
    pub fn grows(&self) -> usize {
        self.grows
    }

    /// Scans whose reach the box could not grow to (at `max_cells`).
    pub fn refused_grows(&self) -> usize {
        self.refused
    }

    /// Grows the box to the reach of a scan from `origin` (m) whose hits are
    /// `rays` and free lengths `free` (m), when `grow` is set: the farthest
    /// cell any ray marks or clears, plus a cell, is inside the inner cells.
    pub(super) fn grow_to_scan(
        &mut self,
        origin: Vector2<f64>,
        rays: &[Option<Vector2<f64>>],
        free: &[f64],
    ) {
        if !self.params.grow {
            return;
        }
        let hits = rays.iter().flatten().map(|p| (p - origin).norm());
        let reach = hits
            .chain(free.iter().take(rays.len()).copied())
            .filter(|d| d.is_finite())
            .fold(0.0f64, f64::max);
        let m = Vector2::repeat(reach + self.resolution);
        self.grow_to_cover(origin - m, origin + m);
    }
}
