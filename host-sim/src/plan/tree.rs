//! The RRT* tree of one planning attempt while it grows: sampling, steering,
//! the cheapest parent, rewiring, and the cheapest join to the goal
//! (docs/maths.md §5).

use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};

use super::RrtParams;
use crate::world::grid::{OccupancyGrid, dist};

/// The edge weight at `p`: `exp(-min(clearance, cap))`, so edges near
/// obstacles cost more (the report's edge cost).
fn weight(grid: &OccupancyGrid, cap: f64, p: [f64; 2]) -> f64 {
    (-grid.clearance(p).min(cap)).exp()
}

/// The RRT* tree while it grows, node 0 the root: positions (m), parents,
/// path costs from the root (m, weighted) and children.
pub(super) struct Growing {
    pub(super) nodes: Vec<[f64; 2]>,
    pub(super) parent: Vec<Option<usize>>,
    pub(super) cost: Vec<f64>,
    children: Vec<Vec<usize>>,
    /// Work done so far: nodes visited by the scans plus points tested along
    /// segments (the upper bound of each test), for [`MAX_TREE_WORK`].
    pub(super) work: u64,
}

/// Most work one RRT* attempt may do, in nodes scanned plus points tested
/// along segments: the tree stops growing once it is spent (deterministic: a
/// count, not a clock). The default settings on the shipped maps use under
/// 1 % of it; `iterations = 1000000` with a `neighbor_radius` spanning the
/// map would use about 1e12 (hours).
pub const MAX_TREE_WORK: u64 = 2_000_000_000;

/// The samples between two calls of the stop callback of [`grow_tree`].
const STOP_POLL: u32 = 64;

/// `params.iterations` RRT* samples from root `s` (goal `g` sampled with
/// probability `params.goal_bias`), on the free cells of `grid`, seeded; fewer
/// once `budget` work ([`MAX_TREE_WORK`] when planning) is spent. `None` when `stop` returned true (polled
/// every few samples).
pub(super) fn grow_tree(
    grid: &OccupancyGrid,
    params: &RrtParams,
    (s, g): ([f64; 2], [f64; 2]),
    seed: u64,
    stop: &dyn Fn() -> bool,
    budget: u64,
) -> Option<Growing> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5252_545f_5354_4152); // "RRT_STAR"
    let mut unif = move || (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let (bx0, by0) = (grid.origin.x, grid.origin.y);
    let (bw, bh) = (
        grid.width as f64 * grid.resolution,
        grid.height as f64 * grid.resolution,
    );
    let mut tree = Growing {
        nodes: vec![s],
        parent: vec![None],
        cost: vec![0.0],
        children: vec![Vec::new()],
        work: 0,
    };
    let mut near: Vec<usize> = Vec::new();
    for i in 0..params.iterations {
        if i % STOP_POLL == 0 && stop() {
            return None;
        }
        if tree.work >= budget {
            break;
        }
        let sample = if unif() < params.goal_bias {
            g
        } else {
            [bx0 + unif() * bw, by0 + unif() * bh]
        };
        tree.extend(grid, params, sample, &mut near);
    }
    Some(tree)
}

/// Points [`OccupancyGrid::segment_free`] tests at most on `a`-`b`.
fn segment_work(grid: &OccupancyGrid, a: [f64; 2], b: [f64; 2]) -> u64 {
    (dist(a, b) / (0.25 * grid.resolution)).ceil().max(1.0) as u64 + 1
}

impl Growing {
    /// One RRT* extension towards `sample`: steer from the nearest node by at
    /// most `params.step`, choose the cheapest parent among the nodes within
    /// `params.neighbor_radius`, and rewire those neighbours through the new
    /// node where that is cheaper. `near` is scratch space.
    fn extend(
        &mut self,
        grid: &OccupancyGrid,
        params: &RrtParams,
        sample: [f64; 2],
        near: &mut Vec<usize>,
    ) {
        let (best, best_d2) = self.nearest(sample);
        self.work += 2 * self.nodes.len() as u64;
        let d = best_d2.sqrt();
        if d < 1e-9 {
            return;
        }
        let from = self.nodes[best];
        let t = (params.step / d).min(1.0);
        let new = [
            from[0] + t * (sample[0] - from[0]),
            from[1] + t * (sample[1] - from[1]),
        ];
        self.work += segment_work(grid, from, new);
        if !grid.is_free(new) || !grid.segment_free(from, new) {
            return;
        }
        let w_new = weight(grid, params.clearance_cap, new);
        let r2 = params.neighbor_radius * params.neighbor_radius;
        near.clear();
        for (k, n) in self.nodes.iter().enumerate() {
            if (n[0] - new[0]).powi(2) + (n[1] - new[1]).powi(2) <= r2 {
                near.push(k);
            }
        }
        // Choose the parent.
        let mut par = best;
        let mut c_new = self.cost[best] + dist(from, new) * w_new;
        for &k in near.iter() {
            let c = self.cost[k] + dist(self.nodes[k], new) * w_new;
            if c < c_new {
                self.work += segment_work(grid, self.nodes[k], new);
            }
            if c < c_new && grid.segment_free(self.nodes[k], new) {
                par = k;
                c_new = c;
            }
        }
        let j = self.nodes.len();
        self.nodes.push(new);
        self.parent.push(Some(par));
        self.cost.push(c_new);
        self.children.push(Vec::new());
        self.children[par].push(j);
        // Rewire.
        for &k in near.iter() {
            if k == par || k == 0 {
                continue;
            }
            let c = c_new
                + dist(new, self.nodes[k]) * weight(grid, params.clearance_cap, self.nodes[k]);
            if c + 1e-12 < self.cost[k] {
                self.work += segment_work(grid, new, self.nodes[k]);
            }
            if c + 1e-12 < self.cost[k] && grid.segment_free(new, self.nodes[k]) {
                self.reparent(k, j, c);
            }
        }
    }

    /// The node nearest `p` and its squared distance, m^2 (linear scan; trees
    /// have a few thousand nodes).
    fn nearest(&self, p: [f64; 2]) -> (usize, f64) {
        let mut best = 0usize;
        let mut best_d2 = f64::INFINITY;
        for (k, n) in self.nodes.iter().enumerate() {
            let d2 = (n[0] - p[0]).powi(2) + (n[1] - p[1]).powi(2);
            if d2 < best_d2 {
                best_d2 = d2;
                best = k;
            }
        }
        (best, best_d2)
    }

    /// Moves node `k` under node `j` with the new path cost `c`; the cost
    /// change goes down `k`'s subtree.
    fn reparent(&mut self, k: usize, j: usize, c: f64) {
        let old = self.parent[k].expect("only the root has no parent");
        self.children[old].retain(|&x| x != k);
        self.children[j].push(k);
        self.parent[k] = Some(j);
        let delta = c - self.cost[k];
        let mut stack = vec![k];
        while let Some(x) = stack.pop() {
            self.cost[x] += delta;
            stack.extend(self.children[x].iter().copied());
        }
    }

    /// The node that joins goal `g` most cheaply (within
    /// `params.neighbor_radius`, by a free segment), and the path cost.
    pub(super) fn join(
        &self,
        grid: &OccupancyGrid,
        params: &RrtParams,
        g: [f64; 2],
    ) -> Option<(usize, f64)> {
        let w_goal = weight(grid, params.clearance_cap, g);
        let mut best: Option<(usize, f64)> = None;
        for (k, n) in self.nodes.iter().enumerate() {
            let d = dist(*n, g);
            if d > params.neighbor_radius {
                continue;
            }
            let c = self.cost[k] + d * w_goal;
            if best.is_none_or(|(_, bc)| c < bc) && grid.segment_free(*n, g) {
                best = Some((k, c));
            }
        }
        best
    }

    /// The node positions from the root to `last`.
    pub(super) fn path_to(&self, last: usize) -> Vec<[f64; 2]> {
        let mut idx = vec![last];
        while let Some(p) = self.parent[*idx.last().expect("non-empty")] {
            idx.push(p);
        }
        idx.reverse();
        idx.iter().map(|&k| self.nodes[k]).collect()
    }
}
