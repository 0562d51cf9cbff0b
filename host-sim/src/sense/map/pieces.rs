//! The controller's obstacles from the map: occupied and near frontier
//! cells merged into rectangles of whole cells (module docs of [`super`]).

use ldcbf_controller::nalgebra::Vector2;

use super::{CellState, OccupancyMap};
use crate::world::Polygon;

impl OccupancyMap {
    /// Whether cell `(i, j)` is unknown with a free 4-neighbour.
    pub(super) fn is_frontier(&self, i: usize, j: usize) -> bool {
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
        // The state first: most cells near the robot are free, and need no
        // distance.
        let wanted = |i: usize, j: usize| match self.state(i, j) {
            CellState::Occupied => (self.centre(i, j) - at).norm() <= radius,
            CellState::Unknown => (self.centre(i, j) - at).norm() <= ur && self.is_frontier(i, j),
            CellState::Free => false,
        };
        let mut rects = Vec::new();
        // Open rectangles: (i_first, i_last, j_first), extended row by row.
        let mut open: Vec<(usize, usize, usize)> = Vec::new();
        for j in j0..=j1 + 1 {
            let mut runs = Vec::new();
            if j <= j1 {
                // Only the row's chord of the disk of radius `reach` (one
                // cell of slack each side) can hold a wanted cell.
                let dy = self.centre(i0, j).y - at.y;
                let half = (reach * reach - dy * dy).max(0.0).sqrt();
                let (lo, hi) = (
                    rng(at.x - half - r, self.origin.x, self.width).max(i0),
                    rng(at.x + half + r, self.origin.x, self.width).min(i1),
                );
                let mut i = lo;
                while i <= hi {
                    if wanted(i, j) {
                        let a = i;
                        while i < hi && wanted(i + 1, j) {
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
