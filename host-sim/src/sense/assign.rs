//! Global nearest neighbour data association: the assignment of tracks to
//! measurements that minimises the summed cost, each at most once, pairs
//! outside the gate never assigned (Blackman and Popoli, "Design and
//! Analysis of Modern Tracking Systems", 1999, section 6.4; the ROS leg
//! tracker of Leigh et al., ICRA 2015, associates so with Munkres).
//!
//! Solved exactly by the Hungarian method in its shortest augmenting path
//! form (Kuhn-Munkres with potentials, O(n^2 m) for n rows and m columns):
//! each track may also take a "missed" column of cost `miss`, so a gated-out
//! pair is never cheaper than leaving both unassigned.

/// The minimum-cost assignment of the rows (tracks) of `cost` to its columns
/// (measurements): `cost[i][j]` is `Some(c)` (finite, >= 0) for a pair inside
/// the gate, `None` outside it. Leaving a row unassigned costs `miss` (>= 0,
/// finite). Returns, per row, its column or `None`. Deterministic (ties go to
/// the lower index).
pub fn assign(cost: &[Vec<Option<f64>>], miss: f64) -> Vec<Option<usize>> {
    let n = cost.len();
    if n == 0 {
        return Vec::new();
    }
    let m = cost.iter().map(Vec::len).max().unwrap_or(0);
    // Columns 0..m are the measurements, m..m+n one "missed" column per row
    // (only its own row may take it at cost `miss`). A gated-out pair costs
    // more than any assignment that avoids it.
    let big = 2.0 * miss + 1.0 + cost.iter().flatten().flatten().fold(0.0, |a: f64, c| a + c);
    let cols = m + n;
    let c = |i: usize, j: usize| -> f64 {
        if j < m {
            cost[i].get(j).copied().flatten().unwrap_or(big)
        } else if j - m == i {
            miss
        } else {
            big
        }
    };
    // Potentials u (rows, 1-based) and v (columns, 1-based), p[j] = row of
    // column j (0 = free), the classic formulation.
    let (mut u, mut v) = (vec![0.0; n + 1], vec![0.0; cols + 1]);
    let mut p = vec![0usize; cols + 1];
    let mut way = vec![0usize; cols + 1];
    for i in 1..=n {
        p[0] = i;
        let mut j0 = 0usize;
        let mut minv = vec![f64::INFINITY; cols + 1];
        let mut used = vec![false; cols + 1];
        // At most `cols` steps: each marks one more column used.
        for _ in 0..=cols {
            used[j0] = true;
            let i0 = p[j0];
            let (mut delta, mut j1) = (f64::INFINITY, 0usize);
            for j in 1..=cols {
                if !used[j] {
                    let cur = c(i0 - 1, j - 1) - u[i0] - v[j];
                    if cur < minv[j] {
                        minv[j] = cur;
                        way[j] = j0;
                    }
                    if minv[j] < delta {
                        delta = minv[j];
                        j1 = j;
                    }
                }
            }
            for j in 0..=cols {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        while j0 != 0 {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
        }
    }
    let mut out = vec![None; n];
    for j in 1..=m {
        let i = p[j];
        if i != 0 && cost[i - 1].get(j - 1).copied().flatten().is_some() {
            out[i - 1] = Some(j - 1);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The cost of an assignment: its pairs plus `miss` per unassigned row.
    fn total(cost: &[Vec<Option<f64>>], miss: f64, a: &[Option<usize>]) -> f64 {
        a.iter()
            .enumerate()
            .map(|(i, j)| j.map_or(miss, |j| cost[i][j].unwrap()))
            .sum()
    }

    /// Every assignment by brute force (rows pick a distinct gated column or
    /// none), the cheapest cost.
    fn brute(cost: &[Vec<Option<f64>>], miss: f64, i: usize, taken: &mut Vec<bool>) -> f64 {
        if i == cost.len() {
            return 0.0;
        }
        let mut best = miss + brute(cost, miss, i + 1, taken);
        for j in 0..taken.len() {
            if let (false, Some(c)) = (taken[j], cost[i][j]) {
                taken[j] = true;
                best = best.min(c + brute(cost, miss, i + 1, taken));
                taken[j] = false;
            }
        }
        best
    }

    #[test]
    fn global_beats_greedy() {
        // Greedy takes (0, 0) at 1.0 and leaves row 1 with nothing in its
        // gate; the global optimum pairs (0, 1) and (1, 0).
        let cost = vec![vec![Some(1.0), Some(1.5)], vec![Some(1.2), None]];
        assert_eq!(assign(&cost, 10.0), vec![Some(1), Some(0)]);
    }

    #[test]
    fn gated_out_pairs_are_never_assigned() {
        let cost = vec![vec![None, None], vec![None, Some(0.3)]];
        assert_eq!(assign(&cost, 1.0), vec![None, Some(1)]);
        assert_eq!(assign(&[], 1.0), Vec::<Option<usize>>::new());
        assert_eq!(assign(&[vec![], vec![]], 1.0), vec![None, None]);
    }

    #[test]
    fn a_pair_dearer_than_two_misses_is_left() {
        // Missing costs 1 per row; pairing row 0 with column 0 at 3.0 is
        // dearer than leaving it (the column then starts its own track).
        let cost = vec![vec![Some(3.0)]];
        assert_eq!(assign(&cost, 1.0), vec![None]);
    }

    proptest! {
        #[test]
        fn the_assignment_is_optimal(
            rows in 0usize..5,
            cols in 0usize..5,
            raw in proptest::collection::vec(proptest::option::weighted(0.7, 0.0f64..10.0), 25),
            miss in 0.0f64..8.0,
        ) {
            let cost: Vec<Vec<Option<f64>>> =
                (0..rows).map(|i| (0..cols).map(|j| raw[i * 5 + j]).collect()).collect();
            let a = assign(&cost, miss);
            prop_assert_eq!(a.len(), rows);
            let mut seen = vec![false; cols];
            for j in a.iter().flatten() {
                prop_assert!(!seen[*j], "column {} twice", j);
                seen[*j] = true;
            }
            let best = brute(&cost, miss, 0, &mut vec![false; cols]);
            prop_assert!((total(&cost, miss, &a) - best).abs() < 1e-9);
        }
    }
}
