//! Planning on the map seen so far (unknown maps): A* over the cells of the
//! perceived occupancy map, with unknown cells traversable but costlier.
//!
//! **Why A\* and not RRT\*.** The perceived map changes every scan and the
//! path is replanned many times a run; A* on the map's own cells
//! ([`grid_search_with`]) is complete on the grid (every passage of connected
//! free cells is found, where RRT* samples may miss a door a few cells wide),
//! deterministic, and its time is bounded by the cell count (each cell is
//! expanded at most once), which is what a bounded time per replan needs. It
//! is the search that D* Lite (S. Koenig and M. Likhachev, "Fast replanning
//! for navigation in unknown terrain", IEEE T-RO 21, 2005) makes incremental;
//! on these maps a full search takes milliseconds, so the replanning is from
//! scratch.
//!
//! **Optimistic planning.** Unknown cells are free for the search (the
//! "freespace assumption" of navigation in unknown terrain), with the cost of
//! entering one multiplied by `unknown_cost`: the path goes through space
//! already seen free when that is not much longer, and towards the unknown
//! only when it must. The edge cost is the known-map planner's
//! (`length * exp(-clearance)` of the cell entered, clearance capped at
//! `clearance_cap`), and the path is shortcut through cells not inflated
//! (unknown cells included) when `shortcut` is set.
//!
//! **Inflation: no gap the barrier cannot pass.** Occupied cells are
//! inflated by the body radius plus `margin`, retried with the smaller
//! margins of [`attempt_margins`] down to the floor
//! ([`RrtParams::map_floor`]: by default the controller's safety margin
//! `delta`, whose barrier keeps the body that far from every piece), so a gap
//! narrower than `2 (body_radius + floor)` between occupied cells is never
//! planned through (Nav2's costmap makes the robot's inscribed radius lethal
//! the same way, docs.nav2.org, "Inflation Layer Parameters").

use ldcbf_controller::nalgebra::Vector2;

use super::{PlanError, RrtParams, attempt_margins, nearest_free, shortcut};
use crate::world::grid::{CellDistances, OccupancyGrid, dist, grid_search_with};

/// A perceived map as the planner reads it: cells of side `resolution` (m),
/// `width x height`, row by row (`j * width + i`), lower-left corner `origin`
/// (m, world frame).
#[derive(Clone, Copy, Debug)]
pub struct CellMap<'a> {
    /// World position of the lower-left corner of cell `(0, 0)`, m.
    pub origin: Vector2<f64>,
    /// Cell side, m.
    pub resolution: f64,
    /// Cells along x.
    pub width: usize,
    /// Cells along y.
    pub height: usize,
    /// Cells seen occupied.
    pub occupied: &'a [bool],
    /// Cells never seen.
    pub unknown: &'a [bool],
}

/// A path on the perceived map.
#[derive(Clone, Debug)]
pub struct MapPlan {
    /// The A* path, start first, goal last, m.
    pub path: Vec<Vector2<f64>>,
    /// The subgoals (after the start; the goal last), m.
    pub subgoals: Vec<Vector2<f64>>,
    /// The grid it was found on (occupied cells inflated by `inflation`).
    pub grid: OccupancyGrid,
    /// Body radius plus the margin that found the path, m.
    pub inflation: f64,
}

/// Plans from `start` to `goal` (m) on `map` for a body of `body_radius` (m)
/// keeping at least `floor` (m) beyond it (module docs): the first margin of
/// [`attempt_margins`] above `floor`, then `floor` itself, that connects the
/// start and the goal. Fails when none does; the error is the last attempt's.
pub fn plan_on_map(
    map: &CellMap<'_>,
    start: Vector2<f64>,
    goal: Vector2<f64>,
    params: &RrtParams,
    body_radius: f64,
    floor: f64,
) -> Result<MapPlan, PlanError> {
    assert_eq!(
        map.occupied.len(),
        map.width * map.height,
        "one flag per cell"
    );
    assert_eq!(
        map.unknown.len(),
        map.width * map.height,
        "one flag per cell"
    );
    let margins = attempt_margins(params.margin)
        .into_iter()
        .filter(|&m| m > floor)
        .chain(core::iter::once(floor));
    let distances = CellDistances::new(map.occupied, map.width, map.resolution);
    let mut last = PlanError::NoPath { nodes: 0 };
    for m in margins {
        match search(map, &distances, start, goal, params, body_radius + m) {
            Ok(p) => return Ok(p),
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// One A* search on `map` (`distances`: its occupied cells' distance
/// transform) with the occupied cells inflated by `inflation` (m).
fn search(
    map: &CellMap<'_>,
    distances: &CellDistances,
    start: Vector2<f64>,
    goal: Vector2<f64>,
    params: &RrtParams,
    inflation: f64,
) -> Result<MapPlan, PlanError> {
    let grid = OccupancyGrid::from_distances(map.origin, distances, inflation);
    let reach = inflation + 2.0 * map.resolution;
    let (s_in, g_in) = ([start.x, start.y], [goal.x, goal.y]);
    let mut entry = false;
    let s = if grid.is_free(s_in) {
        s_in
    } else {
        entry = true;
        nearest_free(&grid, s_in, reach).ok_or(PlanError::StartBlocked)?
    };
    let g = if grid.is_free(g_in) {
        g_in
    } else {
        nearest_free(&grid, g_in, reach).ok_or(PlanError::GoalBlocked)?
    };
    let unknown_cost = params.unknown_cost;
    let (mut path, _) = grid_search_with(&grid, s, g, params.clearance_cap, |k| {
        if map.unknown[k] { unknown_cost } else { 1.0 }
    })
    .ok_or(PlanError::NoPath { nodes: 0 })?;
    if entry {
        path.insert(0, s_in);
    }
    let mut kept = shortcut(&grid, &path, usize::from(entry), params.shortcut);
    if dist(g, g_in) > 1e-12 {
        path.push(g_in);
        kept.push(g_in);
    }
    let to_v = |p: &[f64; 2]| Vector2::new(p[0], p[1]);
    Ok(MapPlan {
        path: path.iter().map(to_v).collect(),
        subgoals: kept.iter().map(to_v).collect(),
        grid,
        inflation,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 m x 2 m map at 0.1 m with a wall across x = 2 m, open for
    /// `y >= gap` (m), everything else as `unknown_all` says.
    fn map_with_wall(gap: f64, unknown_all: bool) -> (Vec<bool>, Vec<bool>) {
        let (w, h) = (40, 20);
        let mut occ = vec![false; w * h];
        for j in 0..h {
            if (j as f64 + 0.5) * 0.1 < gap {
                occ[j * w + 20] = true;
            }
        }
        (occ, vec![unknown_all; w * h])
    }

    fn cell_map<'a>(occ: &'a [bool], unk: &'a [bool]) -> CellMap<'a> {
        CellMap {
            origin: Vector2::zeros(),
            resolution: 0.1,
            width: 40,
            height: 20,
            occupied: occ,
            unknown: unk,
        }
    }

    #[test]
    fn the_path_goes_around_a_seen_wall_through_unknown_space() {
        let (occ, unk) = map_with_wall(1.2, true);
        let p = plan_on_map(
            &cell_map(&occ, &unk),
            Vector2::new(0.5, 0.5),
            Vector2::new(3.5, 0.5),
            &RrtParams::default(),
            0.2,
            0.0,
        )
        .unwrap();
        assert_eq!(*p.subgoals.last().unwrap(), Vector2::new(3.5, 0.5));
        // Every leg stays out of the inflated wall.
        let mut prev = [0.5, 0.5];
        for s in &p.subgoals {
            assert!(p.grid.segment_free(prev, [s.x, s.y]), "{prev:?} -> {s}");
            prev = [s.x, s.y];
        }
        assert!(p.path.iter().any(|q| q.y > 1.2), "goes over the wall's end");
    }

    #[test]
    fn a_closed_wall_is_no_path_and_unknown_space_costs_more() {
        let (occ, unk) = map_with_wall(2.0, true);
        let r = plan_on_map(
            &cell_map(&occ, &unk),
            Vector2::new(0.5, 0.5),
            Vector2::new(3.5, 0.5),
            &RrtParams::default(),
            0.2,
            0.0,
        );
        assert!(matches!(r, Err(PlanError::NoPath { .. })), "{r:?}");
        // Open map: a band at y in [1.4, 1.6) seen free, the rest unknown;
        // with unknown cells 10 times costlier the path detours through the band.
        let occ = vec![false; 800];
        let unk: Vec<bool> = (0..800).map(|k| !(14..16).contains(&(k / 40))).collect();
        let params = RrtParams {
            unknown_cost: 10.0,
            shortcut: false,
            ..RrtParams::default()
        };
        let p = plan_on_map(
            &cell_map(&occ, &unk),
            Vector2::new(0.5, 0.5),
            Vector2::new(3.5, 0.5),
            &params,
            0.2,
            0.0,
        )
        .unwrap();
        assert!(p.path.iter().any(|q| q.y > 1.4), "{:?}", p.path);
        let cheap = plan_on_map(
            &cell_map(&occ, &vec![false; 800]),
            Vector2::new(0.5, 0.5),
            Vector2::new(3.5, 0.5),
            &params,
            0.2,
            0.0,
        )
        .unwrap();
        assert!(cheap.path.iter().all(|q| q.y < 1.0), "{:?}", cheap.path);
    }

    /// A 4 m x 4 m map at 0.1 m, all unknown, with a wall across x = 2 m
    /// holding a door of 6 cells (centres at most 0.3 m from the nearest
    /// wall cell): the door admits an inflation below 0.3 m.
    fn closed_but_a_door() -> (Vec<bool>, Vec<bool>) {
        let (w, h) = (40, 40);
        let mut occ = vec![false; w * h];
        for j in 0..h {
            if !(5..11).contains(&j) {
                occ[j * w + 20] = true;
            }
        }
        (occ, vec![true; w * h])
    }

    #[test]
    fn no_path_through_a_gap_narrower_than_the_floor_allows() {
        let (occ, unk) = closed_but_a_door();
        let map = CellMap {
            height: 40,
            ..cell_map(&occ, &unk)
        };
        let (start, goal) = (Vector2::new(0.5, 0.8), Vector2::new(3.5, 0.8));
        let params = RrtParams::default();
        // Body 0.2 m, floor 0.05 m: the door at the largest margin it
        // admits, 0.075 m (0.15 m closes it).
        let p = plan_on_map(&map, start, goal, &params, 0.2, 0.05).unwrap();
        assert!((p.inflation - 0.275).abs() < 1e-12, "{}", p.inflation);
        // A floor of 0.12 m (inflation 0.32 m) closes it: no path.
        let r = plan_on_map(&map, start, goal, &params, 0.2, 0.12);
        assert!(matches!(r, Err(PlanError::NoPath { .. })), "{r:?}");
    }
}
