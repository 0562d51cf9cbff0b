//! The occupancy grid of a known map: obstacles inflated by a margin, square
//! cells, an exact distance transform of the free cells (Felzenszwalb-Huttenlocher),
//! free segments, and an A* search over the free cells. The planner
//! ([`crate::plan`]) samples its RRT* on it; the layout families
//! ([`crate::world::families`]) check with [`connected`] that a body fits
//! through a layout's passages.
//!
//! All positions are in the world frame W, metres.

use ldcbf_controller::closest_point_point_polygon;
use ldcbf_controller::nalgebra::Vector2;

use crate::world::Polygon;

/// A grid of more than [`MAX_CELLS`] cells was asked for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridTooLarge {
    /// Cells requested.
    pub cells: f64,
}

/// An occupancy grid of inflated obstacles with its distance transform.
#[derive(Clone, Debug)]
pub struct OccupancyGrid {
    /// World position of the lower-left corner of cell `(0, 0)`, m.
    pub origin: Vector2<f64>,
    /// Cell side, m.
    pub resolution: f64,
    /// Cells along x.
    pub width: usize,
    /// Cells along y.
    pub height: usize,
    occupied: Vec<bool>,
    clearance: Vec<f64>,
}

/// Largest number of cells a grid may have (a 1 km x 1 km map at 0.1 m is
/// 10^8; this caps memory at a few hundred MB).
pub const MAX_CELLS: usize = 20_000_000;

impl OccupancyGrid {
    /// Rasterises `obstacles` inflated by `margin` over the box
    /// `[lo, hi]` (m) with square cells of side `resolution`, and computes the
    /// distance transform.
    pub fn build(
        obstacles: &[Polygon],
        margin: f64,
        lo: Vector2<f64>,
        hi: Vector2<f64>,
        resolution: f64,
    ) -> Result<Self, GridTooLarge> {
        let width = ((hi.x - lo.x) / resolution).ceil().max(1.0);
        let height = ((hi.y - lo.y) / resolution).ceil().max(1.0);
        if width * height > MAX_CELLS as f64 {
            return Err(GridTooLarge {
                cells: width * height,
            });
        }
        let (width, height) = (width as usize, height as usize);
        let mut occupied = vec![false; width * height];
        for poly in obstacles {
            // Only the cells of the polygon's bounding box grown by the margin.
            let (mut bl, mut tr) = (
                Vector2::new(f64::INFINITY, f64::INFINITY),
                Vector2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
            );
            for v in poly.vertices() {
                bl = bl.inf(v);
                tr = tr.sup(v);
            }
            let cell = |v: f64, o: f64, n: usize| {
                (((v - o) / resolution).floor().max(0.0) as usize).min(n.saturating_sub(1))
            };
            let (i0, i1) = (
                cell(bl.x - margin, lo.x, width),
                cell(tr.x + margin, lo.x, width),
            );
            let (j0, j1) = (
                cell(bl.y - margin, lo.y, height),
                cell(tr.y + margin, lo.y, height),
            );
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let c = Vector2::new(
                        lo.x + (i as f64 + 0.5) * resolution,
                        lo.y + (j as f64 + 0.5) * resolution,
                    );
                    if closest_point_point_polygon(&c, poly).signed_distance <= margin {
                        occupied[j * width + i] = true;
                    }
                }
            }
        }
        let clearance = distance_transform(&occupied, width, height, resolution);
        Ok(OccupancyGrid {
            origin: lo,
            resolution,
            width,
            height,
            occupied,
            clearance,
        })
    }

    /// The grid of `width x height` cells of side `resolution` (m) whose
    /// lower-left corner is `origin` (m), with the cells whose centre is
    /// within `inflation` (m) of the centre of a `cells` cell (row by row,
    /// `j * width + i`) occupied: a map's occupied cells inflated by the
    /// body (the distance transform of `cells` gives both the inflation and
    /// the clearance beyond it). `cells.len()` must be `width * height`.
    pub fn from_cells(
        origin: Vector2<f64>,
        resolution: f64,
        width: usize,
        height: usize,
        cells: &[bool],
        inflation: f64,
    ) -> Self {
        assert_eq!(cells.len(), width * height, "one flag per cell");
        let d = CellDistances::new(cells, width, resolution);
        Self::from_distances(origin, &d, inflation)
    }

    /// [`OccupancyGrid::from_cells`] from the cells' distance transform
    /// computed once ([`CellDistances`]), for several `inflation`s (m) of one
    /// map; the same grid as `from_cells` with those cells.
    pub fn from_distances(origin: Vector2<f64>, d: &CellDistances, inflation: f64) -> Self {
        let tol = 1e-9 * d.resolution;
        OccupancyGrid {
            origin,
            resolution: d.resolution,
            width: d.width,
            height: d.height,
            occupied: d.d.iter().map(|&x| x <= inflation + tol).collect(),
            clearance: d.d.iter().map(|&x| (x - inflation).max(0.0)).collect(),
        }
    }

    /// The cell containing `p`, if inside the grid.
    pub fn cell_of(&self, p: [f64; 2]) -> Option<(usize, usize)> {
        cell_of(self.origin, self.resolution, self.width, self.height, p)
    }

    /// Whether cell `(i, j)` is occupied (inflated obstacle).
    pub fn is_occupied(&self, i: usize, j: usize) -> bool {
        self.occupied[j * self.width + i]
    }

    /// Whether `p` (m) is inside the grid and in a free cell.
    pub fn is_free(&self, p: [f64; 2]) -> bool {
        self.cell_of(p)
            .is_some_and(|(i, j)| !self.is_occupied(i, j))
    }

    /// Distance from the centre of `p`'s cell to the nearest occupied cell centre,
    /// m (`0` in an occupied cell or outside the grid, `inf` on an empty grid).
    pub fn clearance(&self, p: [f64; 2]) -> f64 {
        self.cell_of(p)
            .map_or(0.0, |(i, j)| self.clearance[j * self.width + i])
    }

    /// Whether the straight segment `a -> b` (m) stays in free cells (points at
    /// most `resolution / 4` apart are checked, both ends included).
    pub fn segment_free(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        segment_all(a, b, self.resolution, |p| self.is_free(p))
    }

    /// Number of occupied cells.
    pub fn occupied_count(&self) -> usize {
        self.occupied.iter().filter(|&&o| o).count()
    }
}

/// The cell `(i, j)` of a `width x height` grid of cells of side
/// `resolution` (m), lower-left corner `origin` (m), that contains `p` (m),
/// if inside the grid.
fn cell_of(
    origin: Vector2<f64>,
    resolution: f64,
    width: usize,
    height: usize,
    p: [f64; 2],
) -> Option<(usize, usize)> {
    let i = ((p[0] - origin.x) / resolution).floor();
    let j = ((p[1] - origin.y) / resolution).floor();
    (i >= 0.0 && j >= 0.0 && i < width as f64 && j < height as f64)
        .then_some((i as usize, j as usize))
}

/// Whether `free` holds at points of the segment `a -> b` (m) at most
/// `resolution / 4` apart, both ends included.
fn segment_all(
    a: [f64; 2],
    b: [f64; 2],
    resolution: f64,
    mut free: impl FnMut([f64; 2]) -> bool,
) -> bool {
    let len = dist(a, b);
    let n = (len / (0.25 * resolution)).ceil().max(1.0) as usize;
    (0..=n).all(|k| {
        let t = k as f64 / n as f64;
        free([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
    })
}

/// The distance from each cell centre of a grid to the nearest flagged cell
/// centre (m, `inf` when none is flagged): the exact distance transform computed
/// once, so that grids of several inflations share it
/// ([`OccupancyGrid::from_distances`]).
#[derive(Clone, Debug)]
pub struct CellDistances {
    resolution: f64,
    width: usize,
    height: usize,
    d: Vec<f64>,
}

impl CellDistances {
    /// The distances of `cells` (row by row, `j * width + i`, `width` cells a
    /// row) with cells of side `resolution` (m).
    pub fn new(cells: &[bool], width: usize, resolution: f64) -> Self {
        let height = cells.len().checked_div(width).unwrap_or(0);
        assert_eq!(cells.len(), width * height, "whole rows of cells");
        CellDistances {
            resolution,
            width,
            height,
            d: distance_transform(cells, width, height, resolution),
        }
    }
}

/// The free test of [`OccupancyGrid::from_cells`] (a cell is occupied when a
/// flagged cell centre is within `inflation` of its centre) answered cell by
/// cell from the flagged cells around it, without the distance transform of
/// the whole grid: for a few questions (is a path still free?) on a large
/// map that changes every scan. Each cell's answer is kept.
#[derive(Clone, Debug)]
pub struct InflatedCells<'a> {
    origin: Vector2<f64>,
    resolution: f64,
    width: usize,
    height: usize,
    cells: &'a [bool],
    inflation: f64,
    /// Per cell: 0 not asked yet, 1 free, 2 occupied.
    known: Vec<u8>,
}

impl<'a> InflatedCells<'a> {
    /// The view of `cells` (`width x height`, row by row, cells of side
    /// `resolution` m, lower-left corner `origin` m) inflated by
    /// `inflation` (m).
    pub fn new(
        origin: Vector2<f64>,
        resolution: f64,
        width: usize,
        height: usize,
        cells: &'a [bool],
        inflation: f64,
    ) -> Self {
        assert_eq!(cells.len(), width * height, "one flag per cell");
        InflatedCells {
            origin,
            resolution,
            width,
            height,
            cells,
            inflation,
            known: vec![0; cells.len()],
        }
    }

    /// Whether `p` (m) is inside the grid and in a free cell: the same answer
    /// as [`OccupancyGrid::is_free`] of `OccupancyGrid::from_cells` with the
    /// same arguments.
    pub fn is_free(&mut self, p: [f64; 2]) -> bool {
        let Some((i, j)) = cell_of(self.origin, self.resolution, self.width, self.height, p) else {
            return false;
        };
        let k = j * self.width + i;
        if self.known[k] == 0 {
            self.known[k] = if self.occupied_within(i, j) { 2 } else { 1 };
        }
        self.known[k] == 1
    }

    /// [`OccupancyGrid::segment_free`] on this view.
    pub fn segment_free(&mut self, a: [f64; 2], b: [f64; 2]) -> bool {
        let r = self.resolution;
        segment_all(a, b, r, |p| self.is_free(p))
    }

    /// Whether a flagged cell centre is within `inflation` of cell `(i, j)`'s
    /// centre, by the distance transform's own arithmetic (the square root of
    /// the integer squared cell distance, times the cell side).
    fn occupied_within(&self, i: usize, j: usize) -> bool {
        let r = self.resolution;
        let limit = self.inflation + 1e-9 * r;
        let reach = (limit / r).floor().max(0.0) as usize;
        let (i0, i1) = (i.saturating_sub(reach), (i + reach).min(self.width - 1));
        let (j0, j1) = (j.saturating_sub(reach), (j + reach).min(self.height - 1));
        (j0..=j1).any(|jj| {
            let dj = jj.abs_diff(j);
            (i0..=i1).any(|ii| {
                let di = ii.abs_diff(i);
                self.cells[jj * self.width + ii] && ((di * di + dj * dj) as f64).sqrt() * r <= limit
            })
        })
    }
}

/// Exact Euclidean distance transform of a binary grid (distance from each cell
/// centre to the nearest `true` cell centre, times `resolution`), by the
/// Felzenszwalb-Huttenlocher lower envelope of parabolas, columns then rows.
fn distance_transform(occ: &[bool], w: usize, h: usize, resolution: f64) -> Vec<f64> {
    const BIG: f64 = 1e20;
    let mut f: Vec<f64> = occ.iter().map(|&o| if o { 0.0 } else { BIG }).collect();
    let mut buf_in = vec![0.0; w.max(h)];
    let mut buf_out = vec![0.0; w.max(h)];
    let mut v = vec![0usize; w.max(h)];
    let mut z = vec![0.0; w.max(h) + 1];
    // Columns (along y).
    for i in 0..w {
        for j in 0..h {
            buf_in[j] = f[j * w + i];
        }
        edt_1d(&buf_in[..h], &mut buf_out[..h], &mut v, &mut z);
        for j in 0..h {
            f[j * w + i] = buf_out[j];
        }
    }
    // Rows (along x).
    for j in 0..h {
        buf_in[..w].copy_from_slice(&f[j * w..(j + 1) * w]);
        edt_1d(&buf_in[..w], &mut buf_out[..w], &mut v, &mut z);
        f[j * w..(j + 1) * w].copy_from_slice(&buf_out[..w]);
    }
    f.iter()
        .map(|&d2| {
            if d2 >= BIG * 0.5 {
                f64::INFINITY
            } else {
                d2.sqrt() * resolution
            }
        })
        .collect()
}

/// One pass of the squared distance transform: `d[q] = min_p (q - p)^2 + f[p]`.
fn edt_1d(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    let sq = |x: usize| (x * x) as f64;
    for q in 1..n {
        // z[0] = -inf and every s is finite, so k never goes below 0.
        let mut s;
        loop {
            let p = v[k];
            s = ((f[q] + sq(q)) - (f[p] + sq(p))) / (2.0 * (q as f64 - p as f64));
            if s <= z[k] && k > 0 {
                k -= 1;
            } else {
                break;
            }
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for q in 0..n {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        let dq = q as f64 - p as f64;
        d[q] = dq * dq + f[p];
    }
}

pub(crate) fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// Whether a disk of radius just under `inflation` (m) can move from `a` to
/// `b` among `obstacles`: both in free cells of an occupancy grid of the
/// obstacles inflated by `inflation` with cells of `resolution` (m), and
/// connected through free cells (8-connected, no corner cutting). A path of
/// free cell centres keeps at least `inflation - resolution / sqrt 2` from
/// every obstacle.
pub fn connected(
    a: Vector2<f64>,
    b: Vector2<f64>,
    obstacles: &[Polygon],
    inflation: f64,
    resolution: f64,
) -> bool {
    let mut lo = a.inf(&b);
    let mut hi = a.sup(&b);
    for o in obstacles {
        for v in o.vertices() {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
    }
    let pad = Vector2::repeat(inflation + 1.0);
    let Ok(grid) = OccupancyGrid::build(obstacles, inflation, lo - pad, hi + pad, resolution)
    else {
        return false;
    };
    let (pa, pb) = ([a.x, a.y], [b.x, b.y]);
    grid.is_free(pa) && grid.is_free(pb) && grid_search(&grid, pa, pb, 0.0).is_some()
}

/// A* over the free cells of `grid` (8-connected, no corner cutting) from the
/// cell of `s` to the cell of `g`, with the report's edge cost (length times
/// `exp(-clearance)` of the cell entered, clearance capped at `cap`) and the
/// straight-line distance times `exp(-cap)` as the (admissible) heuristic.
/// Returns the path `s`, cell centres..., `g` and its cost, or `None` when the
/// two cells are not connected.
pub fn grid_search(
    grid: &OccupancyGrid,
    s: [f64; 2],
    g: [f64; 2],
    cap: f64,
) -> Option<(Vec<[f64; 2]>, f64)> {
    grid_search_with(grid, s, g, cap, |_| 1.0)
}

/// [`grid_search`] with the cost of entering cell `k` (`j * width + i`)
/// multiplied by `factor(k) >= 1` (the heuristic stays admissible): e.g.
/// unknown cells made costlier than cells seen free.
pub fn grid_search_with(
    grid: &OccupancyGrid,
    s: [f64; 2],
    g: [f64; 2],
    cap: f64,
    factor: impl Fn(usize) -> f64,
) -> Option<(Vec<[f64; 2]>, f64)> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let (si, sj) = grid.cell_of(s)?;
    let (gi, gj) = grid.cell_of(g)?;
    let (w, h) = (grid.width, grid.height);
    let idx = |i: usize, j: usize| j * w + i;
    let centre = |k: usize| {
        [
            grid.origin.x + ((k % w) as f64 + 0.5) * grid.resolution,
            grid.origin.y + ((k / w) as f64 + 0.5) * grid.resolution,
        ]
    };
    // Each cell's weight once (an exp per cell, not one per relaxation).
    let weights: Vec<f64> = (0..grid.clearance.len())
        .map(|k| (-grid.clearance[k].min(cap)).exp() * factor(k).max(1.0))
        .collect();
    let weight = |k: usize| weights[k];
    let h_scale = (-cap).exp();
    let goal = idx(gi, gj);
    let heur = |k: usize| dist(centre(k), centre(goal)) * h_scale;
    let mut best = vec![f64::INFINITY; w * h];
    let mut from = vec![usize::MAX; w * h];
    let mut heap = BinaryHeap::new();
    let start = idx(si, sj);
    best[start] = 0.0;
    // Costs are >= 0 and finite: their bits order like the numbers.
    heap.push(Reverse((heur(start).to_bits(), start)));
    while let Some(Reverse((_, k))) = heap.pop() {
        if k == goal {
            let mut cells = vec![k];
            while let Some(&p) = cells.last().map(|&c| &from[c]) {
                if p == usize::MAX {
                    break;
                }
                cells.push(p);
            }
            cells.reverse();
            let mut path = vec![s];
            path.extend(cells.iter().skip(1).map(|&c| centre(c)));
            path.pop(); // the goal cell's centre: `g` itself follows
            path.push(g);
            return Some((path, best[goal]));
        }
        let (i, j) = ((k % w) as isize, (k / w) as isize);
        for (di, dj) in [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (1, -1),
            (-1, 1),
            (-1, -1),
        ] {
            let (ni, nj) = (i + di, j + dj);
            if ni < 0 || nj < 0 || ni >= w as isize || nj >= h as isize {
                continue;
            }
            let (ni, nj) = (ni as usize, nj as usize);
            if grid.is_occupied(ni, nj)
                || (di != 0 && dj != 0)
                    && (grid.is_occupied(ni, j as usize) || grid.is_occupied(i as usize, nj))
            {
                continue;
            }
            let n = idx(ni, nj);
            let step = if di != 0 && dj != 0 {
                core::f64::consts::SQRT_2
            } else {
                1.0
            } * grid.resolution;
            let c = best[k] + step * weight(n);
            if c < best[n] {
                best[n] = c;
                from[n] = k;
                heap.push(Reverse(((c + heur(n)).to_bits(), n)));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::square;

    #[test]
    fn distance_transform_is_exact_on_a_small_grid() {
        let (w, h) = (7, 5);
        let mut occ = vec![false; w * h];
        occ[2 * w + 3] = true;
        occ[0] = true;
        let d = distance_transform(&occ, w, h, 0.5);
        for j in 0..h {
            for i in 0..w {
                let a = (((i as f64 - 3.0).powi(2) + (j as f64 - 2.0).powi(2)).sqrt()) * 0.5;
                let b = ((i * i + j * j) as f64).sqrt() * 0.5;
                assert!((d[j * w + i] - a.min(b)).abs() < 1e-12, "{i} {j}");
            }
        }
        assert!(distance_transform(&[false; 4], 2, 2, 1.0)[3].is_infinite());
    }

    #[test]
    fn grid_inflates_by_the_margin() {
        let obs = [square([0.0, 0.0], 0.5)];
        let g = OccupancyGrid::build(
            &obs,
            0.3,
            Vector2::new(-2.0, -2.0),
            Vector2::new(2.0, 2.0),
            0.1,
        )
        .unwrap();
        assert!(!g.is_free([0.0, 0.0]));
        assert!(!g.is_free([0.75, 0.05]));
        assert!(g.is_free([0.9, 0.05]));
        assert!(!g.is_free([5.0, 0.0]), "outside the grid is blocked");
        assert!((g.clearance([1.55, 0.05]) - 0.7).abs() < 0.11);
        assert!(!g.segment_free([-1.5, 0.0], [1.5, 0.0]));
        assert!(g.segment_free([-1.5, -1.5], [1.5, -1.5]));
    }

    proptest::proptest! {
        /// The lazy view answers every point and segment as the grid built
        /// from the whole distance transform does, and `from_distances`
        /// builds that grid for any inflation.
        #[test]
        fn the_lazy_inflation_agrees_with_the_distance_transform(
            w in 1usize..24,
            h in 1usize..24,
            flags in proptest::collection::vec(proptest::bool::weighted(0.08), 576),
            inflation in 0.0f64..0.6,
            resolution in proptest::sample::select(vec![0.05, 0.1, 0.25]),
            points in proptest::collection::vec((-0.5f64..1.0, -0.5f64..1.0), 12),
        ) {
            let cells = &flags[..w * h];
            let origin = Vector2::new(-0.3, 0.2);
            let grid = OccupancyGrid::from_cells(origin, resolution, w, h, cells, inflation);
            let d = CellDistances::new(cells, w, resolution);
            let again = OccupancyGrid::from_distances(origin, &d, inflation);
            proptest::prop_assert_eq!(&grid.occupied, &again.occupied);
            proptest::prop_assert_eq!(&grid.clearance, &again.clearance);
            let mut lazy = InflatedCells::new(origin, resolution, w, h, cells, inflation);
            let size = [w as f64 * resolution, h as f64 * resolution];
            let at = |(u, v): (f64, f64)| [origin.x + u * size[0] * 1.2, origin.y + v * size[1] * 1.2];
            for p in &points {
                proptest::prop_assert_eq!(lazy.is_free(at(*p)), grid.is_free(at(*p)));
            }
            for pair in points.windows(2) {
                let (a, b) = (at(pair[0]), at(pair[1]));
                proptest::prop_assert_eq!(lazy.segment_free(a, b), grid.segment_free(a, b));
            }
        }
    }
}
