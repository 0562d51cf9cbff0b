//! DBSCAN over the hit points of one scan (the rules are in the module docs of
//! [`super`]).
//!
//! Neighbours are found through a grid of square cells of side `eps` (a
//! point's neighbours lie in its own cell and the 8 around it), and each
//! point enters a cluster's queue at most once, so the memory is O(n) for n
//! points whatever their layout (a queue of every core point's whole
//! neighbourhood grows as n^2 when all points are close: 100,000 rays on a
//! ring of 0.6 m asked for 4 GiB). The time is O(n k) for k neighbours per
//! point: the node bounds n (`ldcbf-ros2`'s ray cap, docs/ros2.md). The labels
//! are those of the textbook algorithm: a cluster's points do not depend on
//! the order in which its queue is walked, and clusters are found in the
//! order of their first core point.

use std::collections::HashMap;

use ldcbf_controller::nalgebra::Vector2;

/// The points of each grid cell of side `eps` (m), for neighbour queries.
/// Points with a coordinate that is not finite are in no cell (they have no
/// neighbour, not even themselves: their distance to anything is NaN).
struct Grid<'a> {
    points: &'a [Vector2<f64>],
    eps: f64,
    eps2: f64,
    /// Cell key -> index into `members`.
    index: HashMap<(i64, i64), usize>,
    /// The points of each cell.
    members: Vec<Vec<usize>>,
    /// The cell of each point (`None`: not finite).
    cell_of: Vec<Option<usize>>,
    /// Points of each cell without a label yet (cells with none are skipped
    /// when a cluster grows: a dense blob costs O(n), not O(n^2)).
    open: Vec<usize>,
}

impl<'a> Grid<'a> {
    fn new(points: &'a [Vector2<f64>], eps: f64) -> Self {
        let mut g = Grid {
            points,
            eps,
            eps2: eps * eps,
            index: HashMap::new(),
            members: Vec::new(),
            cell_of: Vec::with_capacity(points.len()),
            open: Vec::new(),
        };
        for (i, p) in points.iter().enumerate() {
            let c = g.key(p).map(|key| {
                let next = g.members.len();
                let c = *g.index.entry(key).or_insert(next);
                if c == next {
                    g.members.push(Vec::new());
                }
                g.members[c].push(i);
                c
            });
            g.cell_of.push(c);
        }
        g.open = g.members.iter().map(Vec::len).collect();
        g
    }

    /// The cell key of `p` (`as` saturates: far points share the edge
    /// cells, which only costs time, as the distance decides).
    fn key(&self, p: &Vector2<f64>) -> Option<(i64, i64)> {
        (p.x.is_finite() && p.y.is_finite()).then(|| {
            (
                (p.x / self.eps).floor() as i64,
                (p.y / self.eps).floor() as i64,
            )
        })
    }

    /// Calls `f` with each point within `eps` of point `i` (itself
    /// included), until `f` returns `false`; with `open_only`, only in the
    /// cells that still hold a point without a label.
    fn for_each_neighbour(&self, i: usize, open_only: bool, mut f: impl FnMut(usize) -> bool) {
        let p = self.points[i];
        let Some((cx, cy)) = self.key(&p) else {
            return;
        };
        for dx in -1..=1i64 {
            for dy in -1..=1i64 {
                // A cell past i64's range does not exist (no double count).
                let (Some(x), Some(y)) = (cx.checked_add(dx), cy.checked_add(dy)) else {
                    continue;
                };
                let Some(&c) = self.index.get(&(x, y)) else {
                    continue;
                };
                if open_only && self.open[c] == 0 {
                    continue;
                }
                for &j in &self.members[c] {
                    if (self.points[j] - p).norm_squared() <= self.eps2 && !f(j) {
                        return;
                    }
                }
            }
        }
    }

    /// Whether point `i` is a core point: at least `min_points` points
    /// (itself included) within `eps`. Stops counting at `min_points`.
    fn is_core(&self, i: usize, min_points: usize) -> bool {
        let mut count = 0;
        self.for_each_neighbour(i, false, |_| {
            count += 1;
            count < min_points
        });
        count >= min_points
    }

    /// Point `i` got its label.
    fn labelled(&mut self, i: usize) {
        if let Some(c) = self.cell_of[i] {
            self.open[c] -= 1;
        }
    }
}

/// DBSCAN labels: `Some(cluster)` (0-based, in order of discovery) or `None`
/// for noise. See the module docs for the rules.
pub fn dbscan(points: &[Vector2<f64>], eps: f64, min_points: usize) -> Vec<Option<usize>> {
    let n = points.len();
    let mut grid = Grid::new(points, eps);
    let mut label: Vec<Option<usize>> = vec![None; n];
    let mut visited = vec![false; n];
    let mut clusters = 0usize;
    let mut queue: Vec<usize> = Vec::new();
    for i in 0..n {
        if visited[i] {
            continue;
        }
        visited[i] = true;
        if !grid.is_core(i, min_points) {
            continue; // noise unless a later core point reaches it
        }
        let c = clusters;
        clusters += 1;
        label[i] = Some(c);
        grid.labelled(i);
        queue.clear();
        queue.push(i);
        let mut head = 0;
        while head < queue.len() {
            let j = queue[head];
            head += 1;
            // `i` is known to be core; a queued point is expanded when it is
            // core and not visited yet (a noise point seen before is only
            // labelled).
            let expand = j == i || (!visited[j] && grid.is_core(j, min_points));
            visited[j] = true;
            if !expand {
                continue;
            }
            // Each point is queued once: when it first gets a label (a point
            // labelled by an earlier cluster stays a border point of that
            // one, as it was visited then).
            let start = queue.len();
            grid.for_each_neighbour(j, true, |k| {
                if label[k].is_none() {
                    label[k] = Some(c);
                    queue.push(k);
                }
                true
            });
            for &k in &queue[start..] {
                grid.labelled(k);
            }
        }
    }
    label
}

/// The indices of each cluster's points, in cluster order, from [`dbscan`]'s
/// `labels` (noise is in none).
pub fn members(labels: &[Option<usize>]) -> Vec<Vec<usize>> {
    let k = labels.iter().flatten().max().map_or(0, |m| m + 1);
    let mut out = vec![Vec::new(); k];
    for (i, l) in labels.iter().enumerate() {
        if let Some(c) = l {
            out[*c].push(i);
        }
    }
    out
}

/// The points of each DBSCAN cluster, in cluster order.
pub fn clusters(points: &[Vector2<f64>], eps: f64, min_points: usize) -> Vec<Vec<Vector2<f64>>> {
    members(&dbscan(points, eps, min_points))
        .into_iter()
        .map(|m| m.into_iter().map(|i| points[i]).collect())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook DBSCAN (every core point's whole neighbourhood queued,
    /// neighbours by a scan of all points): the labels the grid must give.
    fn textbook(points: &[Vector2<f64>], eps: f64, min_points: usize) -> Vec<Option<usize>> {
        let n = points.len();
        let nb = |i: usize| -> Vec<usize> {
            (0..n)
                .filter(|&j| (points[j] - points[i]).norm_squared() <= eps * eps)
                .collect()
        };
        let mut label = vec![None; n];
        let mut visited = vec![false; n];
        let mut clusters = 0;
        for i in 0..n {
            if visited[i] {
                continue;
            }
            visited[i] = true;
            let first = nb(i);
            if first.len() < min_points {
                continue;
            }
            let c = clusters;
            clusters += 1;
            label[i] = Some(c);
            let mut queue = first;
            let mut head = 0;
            while head < queue.len() {
                let j = queue[head];
                head += 1;
                if label[j].is_none() {
                    label[j] = Some(c);
                }
                if visited[j] {
                    continue;
                }
                visited[j] = true;
                let more = nb(j);
                if more.len() >= min_points {
                    queue.extend(more);
                }
            }
        }
        label
    }

    /// A small deterministic generator (no seed to pin: the layouts are
    /// fixed and many).
    fn layout(k: u64, n: usize) -> Vec<Vector2<f64>> {
        let mut s = k.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| Vector2::new(4.0 * next() - 2.0, 4.0 * next() - 2.0))
            .collect()
    }

    #[test]
    fn grid_labels_equal_the_textbook_ones() {
        for k in 0..200 {
            let n = 5 + (k as usize * 7) % 120;
            let mut pts = layout(k, n);
            if k % 5 == 0 {
                pts.push(Vector2::new(f64::NAN, 0.0));
                pts.push(Vector2::new(f64::INFINITY, 1.0));
                pts.push(Vector2::new(1e300, -1e300));
            }
            for (eps, m) in [(0.3, 3), (0.1, 1), (0.5, 5), (1e-9, 2)] {
                assert_eq!(
                    dbscan(&pts, eps, m),
                    textbook(&pts, eps, m),
                    "{k} {eps} {m}"
                );
            }
        }
    }

    #[test]
    fn a_dense_ring_of_many_points_is_one_cluster_in_linear_memory() {
        // 5,000 points on a ring of radius 0.6 m: each has over 600
        // neighbours within 0.3 m (the textbook queue holds millions of
        // entries); every point is queued once here.
        let n = 5_000;
        let pts: Vec<Vector2<f64>> = (0..n)
            .map(|i| {
                let a = core::f64::consts::TAU * i as f64 / n as f64;
                Vector2::new(0.6 * a.cos(), 0.6 * a.sin())
            })
            .collect();
        let labels = dbscan(&pts, 0.3, 3);
        assert!(labels.iter().all(|l| *l == Some(0)));
    }
}
