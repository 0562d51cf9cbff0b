//! Global planner (docs/maths.md §5): RRT* on an occupancy grid of the known
//! map, whose path becomes a sequence of subgoals for the footstep MPC.
//!
//! All positions are in the world frame W, metres. A room of the simulator that
//! uses only [`crate::world`] (the occupancy grid is
//! [`crate::world::grid`]); its settings are the scenario's `[rrt_star]` table
//! ([`RrtParams`]).
//!
//! # Pipeline ([`plan`])
//!
//! 0. **Inflation, with retries.** The obstacles are inflated by the robot's
//!    body radius plus `margin` (the clearance wanted beyond the body). When no
//!    path is found, the plan is tried again with the margin halved, quartered
//!    and 0 (the body radius alone), on a finer grid each time
//!    ([`attempt_resolution`]), so that every passage at least `2 body_radius +
//!    2 resolution` wide is found; the first path found is kept, and the plan
//!    says which margin it used and after how many attempts.
//! 1. **Occupancy grid** ([`OccupancyGrid::build`]): square cells over the
//!    bounding box of start, goal and obstacles grown by `padding`. A cell is
//!    occupied when its centre is within the inflation of an obstacle (signed
//!    distance `<= inflation`). Everything outside the box counts as occupied.
//!    A start (or goal) in an occupied cell, as a start 0.3 m from a wall is,
//!    is planned from (to) the nearest free cell centre within `inflation + 2
//!    resolution` of it instead: that point becomes the first subgoal (the
//!    goal keeps its place as the last subgoal).
//! 2. **Clearance** ([`OccupancyGrid::clearance`]): an exact Euclidean distance
//!    transform (Felzenszwalb-Huttenlocher, two 1-D passes) gives, for every
//!    cell, the distance from its centre to the nearest occupied cell centre, m.
//!    This is the clearance *beyond* the margin; the true obstacle is about
//!    `margin` farther.
//! 3. **RRT\***, `iterations` samples drawn by a ChaCha8 generator seeded by the
//!    scenario's seed (same seed, same tree, on every platform): a sample is the
//!    goal with probability `goal_bias`, else uniform in the box; the nearest
//!    node is steered towards it by at most `step`; the new node `j` must be in a
//!    free cell and joined by a free segment. Its parent is the node `i` within
//!    `neighbor_radius` that minimises the report's edge cost
//!    `cost(j) = cost(i) + dist(i, j) * exp(-clearance(j))` (clearance capped at
//!    `clearance_cap`), and every neighbour `k` is rewired through `j` when
//!    `cost(j) + dist(j, k) * exp(-clearance(k)) < cost(k)` (costs of `k`'s
//!    subtree are updated). After all samples the goal is joined to the
//!    cheapest reachable node within `neighbor_radius`.
//!    When the tree does not reach the goal (sampling misses narrow passages:
//!    a door 0.1 m wider than the body leaves a free band a few cells wide),
//!    an A* search over the free cells of the same grid (8-connected, no corner
//!    cutting, the same edge cost) gives the path instead: it finds every
//!    passage with connected free cells, and the plan says so (`grid_searched`).
//! 4. **Subgoals**: the path's nodes after the start, the goal last. With
//!    `shortcut`, a greedy pass keeps, from each kept node, the farthest later
//!    node that the straight segment still reaches through free cells.
//!
//! A segment is free when points spaced at most `resolution / 4` along it all
//! fall in free cells.
//!
//! # Following the subgoals
//!
//! The closed loop ([`crate::sim`]) hands the controller the current subgoal
//! instead of the goal and switches to the next one when the CoM is within
//! `switch_radius` of it (checked at each control cycle), so subgoals are
//! reached in order; the last subgoal is the goal itself (reached at the
//! scenario's `success_radius`). Progress, for the stuck detection, is the length
//! of the rest of the path ([`remaining_length`]).

use ldcbf_controller::nalgebra::Vector2;
use serde::{Deserialize, Serialize};

pub mod on_map;
mod tree;

use crate::world::Polygon;
use crate::world::grid::{GridTooLarge, MAX_CELLS, OccupancyGrid, dist, grid_search};
use crate::world::setting::SettingError;
pub use tree::MAX_TREE_WORK;
use tree::grow_tree;

/// Global planner (docs/maths.md §5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Planner {
    /// Walk straight to the goal (the MPC alone).
    #[default]
    None,
    /// RRT* on the known map; its path's nodes are subgoals ([`crate::plan`]).
    #[value(name = "rrt_star")]
    RrtStar,
}

impl Planner {
    /// The name used in files (`none`, `rrt_star`).
    pub fn name(self) -> &'static str {
        match self {
            Planner::None => "none",
            Planner::RrtStar => "rrt_star",
        }
    }
}

/// RRT* settings: the scenario's `[rrt_star]` table. Lengths in metres.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct RrtParams {
    /// Side of a grid cell, m.
    pub resolution: f64,
    /// Clearance wanted beyond the robot's body radius, m: the obstacles are
    /// inflated by `body_radius + margin` (retried down to the body radius
    /// alone when no path is found; see the module docs).
    pub margin: f64,
    /// The planning box is the bounding box of start, goal and obstacles grown by
    /// this much on every side, m.
    pub padding: f64,
    /// Number of samples (a fixed number: the result depends only on the seed).
    pub iterations: u32,
    /// Largest edge added towards a sample (steering distance), m.
    pub step: f64,
    /// Radius of the neighbourhood searched for the parent and for rewiring, m.
    pub neighbor_radius: f64,
    /// Probability that a sample is the goal, in [0, 1).
    pub goal_bias: f64,
    /// Clearance above this counts as this much in `exp(-clearance)`, m.
    /// `inf` is the report's cost exactly; it rewards every metre of open space,
    /// so paths swing out to the edges of the planning box. The default 0.5 m
    /// keeps the report's preference for clearance near obstacles and the
    /// shortest path elsewhere.
    pub clearance_cap: f64,
    /// Replace the path by its greedy shortcut through free cells.
    pub shortcut: bool,
    /// The next subgoal is taken when the CoM is within this of the current one, m.
    pub switch_radius: f64,
    /// Planning on the perceived map ([`on_map`]): the cost of a step into an
    /// unknown cell is this many times that of a step into a cell seen free
    /// (>= 1; optimistic planning: unknown space is traversable, but paths
    /// through space already seen are preferred).
    pub unknown_cost: f64,
    /// Planning on the perceived map: the path is checked against the map
    /// every this many seconds of simulated time (and replanned when it crosses
    /// an inflated occupied cell), s.
    pub replan_period: f64,
    /// Planning on the perceived map: the smallest clearance beyond the body
    /// radius a path may keep (the last of the margin attempts), m. Unset: the
    /// controller's safety margin `delta` (see [`RrtParams::map_floor`]), so
    /// no path goes through a gap narrower than the controller's barrier
    /// lets the body through.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub map_min_margin: Option<f64>,
}

impl Default for RrtParams {
    fn default() -> Self {
        RrtParams {
            resolution: 0.1,
            margin: 0.15,
            padding: 1.0,
            iterations: 3000,
            step: 0.5,
            neighbor_radius: 1.2,
            goal_bias: 0.05,
            clearance_cap: 0.5,
            shortcut: true,
            switch_radius: 0.4,
            unknown_cost: 2.0,
            replan_period: 0.25,
            map_min_margin: None,
        }
    }
}

impl RrtParams {
    /// The smallest clearance beyond the body radius a path on the perceived
    /// map keeps, m: `map_min_margin` when set, else the controller's safety
    /// margin `delta` (m), capped at `margin`.
    pub fn map_floor(&self, delta: f64) -> f64 {
        self.map_min_margin
            .unwrap_or(delta)
            .min(self.margin)
            .max(0.0)
    }

    /// Checks every field; the error names the bad one and says why.
    pub fn validate(&self) -> Result<(), SettingError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !(pos(self.resolution) && self.resolution <= 10.0) {
            return Err(SettingError::new("resolution", "must be in (0, 10] m"));
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return Err(SettingError::new("margin", "must be finite and >= 0"));
        }
        if !(self.padding.is_finite() && self.padding >= 0.0) {
            return Err(SettingError::new("padding", "must be finite and >= 0"));
        }
        if !(1..=1_000_000).contains(&self.iterations) {
            return Err(SettingError::new("iterations", "must be in 1..=1000000"));
        }
        if !pos(self.step) {
            return Err(SettingError::new("step", "must be finite and > 0"));
        }
        if !(pos(self.neighbor_radius) && self.neighbor_radius >= self.step) {
            return Err(SettingError::new(
                "neighbor_radius",
                "must be finite and >= step",
            ));
        }
        if !(self.goal_bias >= 0.0 && self.goal_bias < 1.0) {
            return Err(SettingError::new("goal_bias", "must be in [0, 1)"));
        }
        if self.clearance_cap.is_nan() || self.clearance_cap < 0.0 {
            return Err(SettingError::new(
                "clearance_cap",
                "must be >= 0 (inf allowed)",
            ));
        }
        if !pos(self.switch_radius) {
            return Err(SettingError::new("switch_radius", "must be finite and > 0"));
        }
        if !(self.unknown_cost.is_finite() && self.unknown_cost >= 1.0) {
            return Err(SettingError::new("unknown_cost", "must be finite and >= 1"));
        }
        if !(pos(self.replan_period) && self.replan_period <= 60.0) {
            return Err(SettingError::new("replan_period", "must be in (0, 60] s"));
        }
        if self
            .map_min_margin
            .is_some_and(|m| !(m.is_finite() && m >= 0.0))
        {
            return Err(SettingError::new(
                "map_min_margin",
                "must be finite and >= 0",
            ));
        }
        Ok(())
    }
}

/// The RRT* tree. Node 0 is the start.
#[derive(Clone, Debug, Default)]
pub struct Tree {
    /// Node positions, m (world).
    pub nodes: Vec<Vector2<f64>>,
    /// Parent of each node (`None` for the start).
    pub parent: Vec<Option<usize>>,
    /// Cost of the path from the start to each node (the report's edge cost, m).
    pub cost: Vec<f64>,
}

/// A finished RRT* route on the known map: the grid, the tree, the path and
/// the subgoals the controller walks through (not the controller's
/// [`ldcbf_controller::Plan`], the MPC's plan of one cycle).
#[derive(Clone, Debug)]
pub struct Route {
    /// The grid it was planned on.
    pub grid: OccupancyGrid,
    /// The whole tree (for figure 8).
    pub tree: Tree,
    /// The RRT* path, start first, goal last, m.
    pub path: Vec<Vector2<f64>>,
    /// Cost of that path (report's edge cost), m.
    pub cost: f64,
    /// The subgoals handed to the controller in order (after the start; the goal
    /// last), m: the path's nodes, shortcut when `shortcut` is set.
    pub subgoals: Vec<Vector2<f64>>,
    /// Inflation of the grid the path was found on: body radius + `margin_used`, m.
    pub inflation: f64,
    /// The margin beyond the body radius that found the path, m.
    pub margin_used: f64,
    /// Attempts made (1 = found with the scenario's margin).
    pub attempts: u32,
    /// The nearest free cell centre the plan starts from when the start sat in
    /// the inflated zone (the first subgoal), m.
    pub entry: Option<Vector2<f64>>,
    /// The RRT* tree did not reach the goal and the path came from the grid
    /// search (A*) on the same grid and cost ([`plan`]).
    pub grid_searched: bool,
}

impl Route {
    /// Euclidean length of the subgoal polyline from `start`, m.
    pub fn subgoal_length(&self, start: Vector2<f64>) -> f64 {
        polyline_length(start, &self.subgoals)
    }
}

/// Length of the polyline `from -> points[0] -> ... -> points[last]`, m.
pub fn polyline_length(from: Vector2<f64>, points: &[Vector2<f64>]) -> f64 {
    let mut prev = from;
    let mut len = 0.0;
    for p in points {
        len += (p - prev).norm();
        prev = *p;
    }
    len
}

/// Progress measure along a subgoal sequence: the distance from `p` to subgoal
/// `current`, plus the length of the polyline from it through the later
/// subgoals, m. With a single subgoal (the goal) it is the distance to the goal.
/// Switching to the next subgoal never increases it (triangle inequality).
pub fn remaining_length(p: Vector2<f64>, subgoals: &[Vector2<f64>], current: usize) -> f64 {
    match subgoals.get(current) {
        None => 0.0,
        Some(s) => (p - s).norm() + polyline_length(*s, &subgoals[current + 1..]),
    }
}

/// Why no plan was made.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanError {
    /// The settings are invalid (the field of `[rrt_star]`, and why).
    Settings(SettingError),
    /// The grid would have more than [`MAX_CELLS`] cells.
    GridTooLarge {
        /// Cells requested.
        cells: f64,
    },
    /// The start is in an inflated obstacle (or outside the grid).
    StartBlocked,
    /// The goal is in an inflated obstacle (or outside the grid).
    GoalBlocked,
    /// No node of the tree reaches the goal after all iterations.
    NoPath {
        /// Tree size at the end.
        nodes: usize,
    },
    /// The caller's stop callback asked to stop (Ctrl-C).
    Stopped,
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlanError::Settings(e) => write!(f, "rrt_star.{e}"),
            PlanError::GridTooLarge { cells } => write!(
                f,
                "the occupancy grid would have {cells:.0} cells (max {MAX_CELLS}); raise rrt_star.resolution"
            ),
            PlanError::StartBlocked => f.write_str(
                "no free cell near the start (the body radius and rrt_star.margin cover it)",
            ),
            PlanError::GoalBlocked => f.write_str(
                "no free cell near the goal (the body radius and rrt_star.margin cover it)",
            ),
            PlanError::NoPath { nodes } => write!(
                f,
                "no path to the goal in a tree of {nodes} nodes, even with the obstacles inflated by the body radius alone (more rrt_star.iterations may help)"
            ),
            PlanError::Stopped => f.write_str("planning stopped"),
        }
    }
}

impl std::error::Error for PlanError {}

impl From<GridTooLarge> for PlanError {
    fn from(e: GridTooLarge) -> Self {
        PlanError::GridTooLarge { cells: e.cells }
    }
}

/// The margins beyond the body radius tried in order: `margin`, `margin / 2`,
/// `margin / 4`, 0 (just `0` when `margin` is 0), m.
pub fn attempt_margins(margin: f64) -> Vec<f64> {
    if margin > 0.0 {
        vec![margin, 0.5 * margin, 0.25 * margin, 0.0]
    } else {
        vec![0.0]
    }
}

/// Grid resolution of an attempt with `margin` beyond the body, m: at most
/// `resolution`, at most half the margin, and not below a quarter of
/// `resolution` nor 2.5 cm (so the last attempt, margin 0, still has cell
/// centres across a passage 0.1 m wider than the body).
pub fn attempt_resolution(resolution: f64, margin: f64) -> f64 {
    resolution.min((0.5 * margin).max(0.25 * resolution).max(0.025))
}

/// Plans from `start` to `goal` around `obstacles` for a robot whose body is a
/// disk of `body_radius` (m), retrying with smaller margins (see the module
/// docs). The same arguments always give the same plan; the error is the last
/// attempt's. Each attempt's tree does at most [`MAX_TREE_WORK`] work,
/// and `stop` is polled every few samples: when it returns true the planning
/// ends with [`PlanError::Stopped`] (the closed loop passes its cancel flag).
pub fn plan(
    (start, goal): (Vector2<f64>, Vector2<f64>),
    obstacles: &[Polygon],
    params: &RrtParams,
    body_radius: f64,
    seed: u64,
    stop: &dyn Fn() -> bool,
) -> Result<Route, PlanError> {
    params.validate().map_err(PlanError::Settings)?;
    if !(body_radius.is_finite() && body_radius >= 0.0) {
        return Err(PlanError::Settings(SettingError::new(
            "margin",
            format!("the body radius must be finite and >= 0, got {body_radius}"),
        )));
    }
    let margins = attempt_margins(params.margin);
    let mut last = PlanError::NoPath { nodes: 0 };
    for (k, &m) in margins.iter().enumerate() {
        let res = attempt_resolution(params.resolution, m);
        let attempt = Attempt {
            inflation: body_radius + m,
            resolution: res,
            seed,
            stop,
        };
        match plan_once(start, goal, obstacles, params, &attempt) {
            Ok(mut p) => {
                p.margin_used = m;
                p.attempts = k as u32 + 1;
                return Ok(p);
            }
            Err(e @ (PlanError::GridTooLarge { .. } | PlanError::Stopped)) => return Err(e),
            Err(e) => last = e,
        }
    }
    Err(last)
}

/// The subgoals of `path` (start first): `path[1..=first]` as they are, then,
/// with `enabled`, a greedy pass that keeps, from each kept node, the farthest
/// later node the straight segment reaches through free cells of `grid`
/// (without, every later node).
fn shortcut(grid: &OccupancyGrid, path: &[[f64; 2]], first: usize, enabled: bool) -> Vec<[f64; 2]> {
    let mut kept: Vec<[f64; 2]> = path[1..=first].to_vec();
    if enabled {
        let mut i = first;
        while i + 1 < path.len() {
            let mut j = path.len() - 1;
            while j > i + 1 && !grid.segment_free(path[i], path[j]) {
                j -= 1;
            }
            kept.push(path[j]);
            i = j;
        }
    } else {
        kept.extend_from_slice(&path[first + 1..]);
    }
    kept
}

/// The nearest free cell centre to `p` within `reach` (m), if any.
fn nearest_free(grid: &OccupancyGrid, p: [f64; 2], reach: f64) -> Option<[f64; 2]> {
    let r = (reach / grid.resolution).ceil() as isize + 1;
    let (ci, cj) = grid.cell_of(p)?;
    let mut best: Option<([f64; 2], f64)> = None;
    for dj in -r..=r {
        for di in -r..=r {
            let (i, j) = (ci as isize + di, cj as isize + dj);
            if i < 0 || j < 0 || i >= grid.width as isize || j >= grid.height as isize {
                continue;
            }
            let (i, j) = (i as usize, j as usize);
            if grid.is_occupied(i, j) {
                continue;
            }
            let c = [
                grid.origin.x + (i as f64 + 0.5) * grid.resolution,
                grid.origin.y + (j as f64 + 0.5) * grid.resolution,
            ];
            let d = dist(c, p);
            if d <= reach && best.is_none_or(|(_, bd)| d < bd) {
                best = Some((c, d));
            }
        }
    }
    best.map(|(c, _)| c)
}

/// What one attempt of [`plan`] varies, and what it shares.
struct Attempt<'a> {
    /// The obstacles' inflation, m.
    inflation: f64,
    /// The grid's cell side, m.
    resolution: f64,
    /// The tree's seed.
    seed: u64,
    /// The caller's stop callback.
    stop: &'a dyn Fn() -> bool,
}

/// One RRT* attempt on a grid of obstacles inflated by `inflation` (m) with
/// cells of `resolution` (m): the grid, its free start and goal, the tree,
/// the path to the goal (the grid search when the tree misses it) and the
/// subgoals.
fn plan_once(
    start: Vector2<f64>,
    goal: Vector2<f64>,
    obstacles: &[Polygon],
    params: &RrtParams,
    attempt: &Attempt<'_>,
) -> Result<Route, PlanError> {
    let (inflation, resolution, seed) = (attempt.inflation, attempt.resolution, attempt.seed);
    let grid = planning_grid(start, goal, obstacles, params, inflation, resolution)?;
    let reach = inflation + 2.0 * resolution;
    let goal_in = [goal.x, goal.y];
    let mut entry = None;
    let s = if grid.is_free([start.x, start.y]) {
        [start.x, start.y]
    } else {
        let e = nearest_free(&grid, [start.x, start.y], reach).ok_or(PlanError::StartBlocked)?;
        entry = Some(Vector2::new(e[0], e[1]));
        e
    };
    let g = if grid.is_free(goal_in) {
        goal_in
    } else {
        nearest_free(&grid, goal_in, reach).ok_or(PlanError::GoalBlocked)?
    };
    let tree = grow_tree(&grid, params, (s, g), seed, attempt.stop, MAX_TREE_WORK)
        .ok_or(PlanError::Stopped)?;
    let to_v = |p: [f64; 2]| Vector2::new(p[0], p[1]);
    let (mut path, total, searched) = match tree.join(&grid, params, g) {
        Some((last, total)) => (tree.path_to(last), total, false),
        // Sampling misses narrow passages (a door 0.1 m wider than the body
        // leaves a free band of a few cells): the grid search is complete on
        // the grid, so a passage with free cells through it is found.
        None => match grid_search(&grid, s, g, params.clearance_cap) {
            Some((path, cost)) => (path, cost, true),
            None => {
                return Err(PlanError::NoPath {
                    nodes: tree.nodes.len(),
                });
            }
        },
    };
    if dist(*path.last().expect("non-empty"), g) > 1e-12 {
        path.push(g);
    }
    if entry.is_some() {
        path.insert(0, [start.x, start.y]);
    }
    // The grid's free space ends `inflation` from the obstacles; from the
    // nearest free cell the last leg goes to the goal itself.
    let goal_leg = dist(g, goal_in) > 1e-12;
    // From an entry point the first leg (start -> entry) is kept as is: the
    // start is in the inflated zone, so no shortcut may begin there.
    let first = usize::from(entry.is_some());
    let mut kept = shortcut(&grid, &path, first, params.shortcut);
    if goal_leg {
        path.push(goal_in);
        kept.push(goal_in);
    }
    Ok(Route {
        tree: Tree {
            nodes: tree.nodes.iter().map(|&p| to_v(p)).collect(),
            parent: tree.parent,
            cost: tree.cost,
        },
        grid,
        path: path.iter().map(|&p| to_v(p)).collect(),
        cost: total,
        subgoals: kept.iter().map(|&p| to_v(p)).collect(),
        inflation,
        margin_used: 0.0, // set by `plan`
        attempts: 1,
        entry,
        grid_searched: searched,
    })
}

/// The occupancy grid of one attempt: the box of start, goal and obstacles,
/// padded by `params.padding + inflation` (m), obstacles inflated by
/// `inflation`, cells of `resolution` (m).
fn planning_grid(
    start: Vector2<f64>,
    goal: Vector2<f64>,
    obstacles: &[Polygon],
    params: &RrtParams,
    inflation: f64,
    resolution: f64,
) -> Result<OccupancyGrid, PlanError> {
    let mut lo = start.inf(&goal);
    let mut hi = start.sup(&goal);
    for o in obstacles {
        for v in o.vertices() {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
    }
    let pad = Vector2::repeat(params.padding + inflation);
    OccupancyGrid::build(obstacles, inflation, lo - pad, hi + pad, resolution)
        .map_err(PlanError::from)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::square;
    use ldcbf_controller::closest_point_point_polygon;

    #[test]
    fn plan_goes_around_and_is_deterministic() {
        let obs = [square([2.5, 0.0], 1.0)];
        let p = RrtParams {
            iterations: 1200,
            ..RrtParams::default()
        };
        let (s, g) = (Vector2::new(0.0, 0.0), Vector2::new(5.0, 0.0));
        let a = plan((s, g), &obs, &p, 0.25, 3, &|| false).unwrap();
        let b = plan((s, g), &obs, &p, 0.25, 3, &|| false).unwrap();
        assert_eq!((a.attempts, a.margin_used, a.inflation), (1, 0.15, 0.4));
        assert_eq!(a.subgoals, b.subgoals);
        assert_eq!(a.tree.nodes, b.tree.nodes);
        assert_eq!(*a.subgoals.last().unwrap(), g);
        let mut prev = s;
        for q in &a.subgoals {
            assert!(a.grid.segment_free([prev.x, prev.y], [q.x, q.y]));
            prev = *q;
        }
        assert!(a.subgoal_length(s) > 5.0);
        // Costs are consistent with parents after rewiring.
        for k in 1..a.tree.nodes.len() {
            let par = a.tree.parent[k].unwrap();
            let w = (-a
                .grid
                .clearance([a.tree.nodes[k].x, a.tree.nodes[k].y])
                .min(p.clearance_cap))
            .exp();
            let c = a.tree.cost[par] + (a.tree.nodes[k] - a.tree.nodes[par]).norm() * w;
            assert!((c - a.tree.cost[k]).abs() < 1e-9, "node {k}");
        }
    }

    #[test]
    fn planning_stops_when_asked_and_its_work_is_bounded() {
        let obs = [square([2.5, 0.0], 1.0)];
        let (s, g) = (Vector2::new(0.0, 0.0), Vector2::new(5.0, 0.0));
        let huge = RrtParams {
            iterations: 1_000_000,
            neighbor_radius: 1e6,
            ..RrtParams::default()
        };
        let polls = std::cell::Cell::new(0);
        let stop = || {
            polls.set(polls.get() + 1);
            polls.get() > 3
        };
        let stopped = plan((s, g), &obs, &huge, 0.25, 3, &stop);
        assert!(matches!(stopped, Err(PlanError::Stopped)), "{stopped:?}");
        assert_eq!(polls.get(), 4);
        // A small budget stops the growth long before the million samples.
        let grid = planning_grid(s, g, &obs, &huge, 0.4, 0.1).unwrap();
        let budget = 5_000_000;
        let t = grow_tree(&grid, &huge, ([0.0, 0.0], [5.0, 0.0]), 3, &|| false, budget).unwrap();
        assert!(
            t.nodes.len() > 10 && t.nodes.len() < 10_000,
            "{}",
            t.nodes.len()
        );
        assert!(t.work >= budget, "{}", t.work);
    }

    #[test]
    fn blocked_start_is_an_error() {
        let obs = [square([0.0, 0.0], 1.0)];
        let e = plan(
            (Vector2::new(0.0, 0.0), Vector2::new(5.0, 0.0)),
            &obs,
            &RrtParams::default(),
            0.25,
            0,
            &|| false,
        )
        .unwrap_err();
        assert_eq!(e, PlanError::StartBlocked);
    }

    /// A closed room (x in [-1, 5], y in [-4, 4]) split by a thin wall (5 cm)
    /// at x = 2 with a door of `width` centred at `y`: the door is the only
    /// way from x < 2 to x > 2.
    fn doorway(width: f64, y: f64) -> Vec<Polygon> {
        let r = |x0: f64, y0: f64, x1: f64, y1: f64| {
            Polygon::new(&[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]).unwrap()
        };
        vec![
            r(2.0, -4.0, 2.05, y - 0.5 * width),
            r(2.0, y + 0.5 * width, 2.05, 4.0),
            r(-1.0, -4.2, 5.0, -4.0),
            r(-1.0, 4.0, 5.0, 4.2),
            r(-1.2, -4.2, -1.0, 4.2),
            r(5.0, -4.2, 5.2, 4.2),
        ]
    }

    /// Smallest distance of the subgoal polyline (from `s`) to the obstacles, m.
    fn path_clearance(s: Vector2<f64>, sub: &[Vector2<f64>], obs: &[Polygon]) -> f64 {
        let mut prev = s;
        let mut m = f64::INFINITY;
        for q in sub {
            for k in 0..=200 {
                let p = prev + (q - prev) * (k as f64 / 200.0);
                for o in obs {
                    m = m.min(closest_point_point_polygon(&p, o).signed_distance);
                }
            }
            prev = *q;
        }
        m
    }

    #[test]
    fn every_door_the_body_fits_is_found() {
        let r = 0.25;
        let (s, g) = (Vector2::new(0.0, 0.0), Vector2::new(4.0, 0.3));
        for (w, y) in [
            (2.0 * r + 0.1, 1.3),
            (0.7, -1.1),
            (0.8, 2.0),
            (1.0, -2.6),
            (1.6, 0.0),
        ] {
            let obs = doorway(w, y);
            let p = plan((s, g), &obs, &RrtParams::default(), r, 7, &|| false)
                .unwrap_or_else(|e| panic!("door {w} m at y = {y}: {e}"));
            let c = path_clearance(s, &p.subgoals, &obs);
            assert!(c >= r - 1e-9, "door {w} m: path {c} m from a wall");
            assert!(p.inflation >= r);
            // Wide doors keep the whole margin; the narrowest needs retries.
            if w >= 1.0 {
                assert_eq!(p.attempts, 1, "door {w} m");
            }
            if w < 2.0 * (r + 0.15) {
                assert!(p.attempts > 1, "door {w} m needs a smaller margin");
            }
        }
        // A door narrower than the body is not passed.
        let obs = doorway(2.0 * r - 0.02, 0.0);
        assert!(plan((s, g), &obs, &RrtParams::default(), r, 7, &|| false).is_err());
    }

    #[test]
    fn a_start_near_a_wall_plans_from_the_nearest_free_cell() {
        // Centre 0.3-0.6 m from the wall face, facing it; the goal behind it.
        let obs = doorway(0.9, 2.5);
        for d in [0.3, 0.45, 0.6] {
            let s = Vector2::new(2.0 - d, 0.0);
            let g = Vector2::new(4.0, 0.0);
            let p = plan((s, g), &obs, &RrtParams::default(), 0.25, 11, &|| false)
                .unwrap_or_else(|e| panic!("start {d} m from the wall: {e}"));
            let blocked = d < 0.25 + 0.15 + 0.05;
            assert_eq!(p.entry.is_some(), blocked, "start {d} m");
            if let Some(e) = p.entry {
                assert_eq!(p.subgoals[0], e);
                assert!((e - s).norm() <= p.inflation + 2.0 * p.grid.resolution);
            }
            assert_eq!(*p.subgoals.last().unwrap(), g);
            assert!(path_clearance(s, &p.subgoals, &obs) >= 0.25 - 1e-9);
        }
    }

    #[test]
    fn remaining_length_never_grows_at_a_switch() {
        let sg = [
            Vector2::new(1.0, 0.0),
            Vector2::new(1.0, 1.0),
            Vector2::new(3.0, 1.0),
        ];
        let p = Vector2::new(0.8, 0.1);
        assert!(remaining_length(p, &sg, 1) <= remaining_length(p, &sg, 0));
        assert!((remaining_length(Vector2::new(0.0, 0.0), &sg, 0) - 4.0).abs() < 1e-12);
    }
}
