//! DBSCAN over the hit points of one scan (the rules are in the module docs of
//! [`super`]).

use ldcbf_controller::nalgebra::Vector2;

/// DBSCAN labels: `Some(cluster)` (0-based, in order of discovery) or `None`
/// for noise. See the module docs for the rules.
pub fn dbscan(points: &[Vector2<f64>], eps: f64, min_points: usize) -> Vec<Option<usize>> {
    let n = points.len();
    let eps2 = eps * eps;
    let neighbours = |i: usize| -> Vec<usize> {
        (0..n)
            .filter(|&j| (points[j] - points[i]).norm_squared() <= eps2)
            .collect()
    };
    let mut label: Vec<Option<usize>> = vec![None; n];
    let mut visited = vec![false; n];
    let mut clusters = 0usize;
    for i in 0..n {
        if visited[i] {
            continue;
        }
        visited[i] = true;
        let nb = neighbours(i);
        if nb.len() < min_points {
            continue; // noise unless a later core point reaches it
        }
        let c = clusters;
        clusters += 1;
        label[i] = Some(c);
        let mut queue = nb;
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
            let nbj = neighbours(j);
            if nbj.len() >= min_points {
                queue.extend(nbj);
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
