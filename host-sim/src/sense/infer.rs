//! The obstacles inferred from one scan: chains of neighbouring hits of one
//! cluster, split and merge into segments, convex pieces extruded away from
//! the sensor, and the merge of neighbouring pieces (module docs of [`super`]);
//! and the former one-hull-per-cluster inference ([`cluster_polygon`]).

use ldcbf_controller::geometry::{closest_point_point_polygon, convex_hull_into};
use ldcbf_controller::nalgebra::Vector2;

use super::{LidarParams, dbscan, ray_angle, ray_direction};
use crate::world::{MAX_VERTICES, Polygon};

/// Inferred obstacles of one scan taken from `origin` (m, world frame) with
/// the sensor's zero angle along `heading` (rad): `rays[i]` is ray `i`'s hit
/// point (m) or `None` (see [`Lidar::scan_rays`](super::Lidar::scan_rays)). The convex pieces of every
/// DBSCAN cluster, by breakpoints, split-and-merge and extrusion away from the
/// sensor (module docs). Deterministic: the same scan gives the same pieces.
pub fn infer_obstacles(
    rays: &[Option<Vector2<f64>>],
    origin: Vector2<f64>,
    heading: f64,
    params: &LidarParams,
) -> Vec<Polygon> {
    let n = rays.len();
    if n == 0 {
        return Vec::new();
    }
    let tol = free_tolerance(params);
    // Hits far enough from the sensor to be kept out of a piece, and DBSCAN
    // over them.
    let usable: Vec<usize> = (0..n)
        .filter(|&i| rays[i].is_some_and(|p| (p - origin).norm() > tol + 1e-3))
        .collect();
    let pts: Vec<Vector2<f64>> = usable.iter().map(|&i| rays[i].unwrap_or(origin)).collect();
    let mut label: Vec<Option<usize>> = vec![None; n];
    for (k, l) in dbscan(&pts, params.eps, params.min_points)
        .into_iter()
        .enumerate()
    {
        label[usable[k]] = l;
    }
    let chains = breakpoint_chains(rays, origin, params, |k| label[k]);
    let mut out = Vec::new();
    let ctx = PieceContext {
        origin,
        heading,
        rays: n,
        tol,
        params,
    };
    let mut pieces: Vec<(Option<usize>, Piece)> = Vec::new();
    for chain in chains {
        let p: Vec<Vector2<f64>> = chain.iter().filter_map(|&u| rays[u % n]).collect();
        let mut segs = Vec::new();
        for (a, b) in split_and_merge(&p, params.line_tolerance) {
            segment_piece(&ctx, &chain[a..=b], &p[a..=b], &mut segs);
        }
        let l = label[chain[0] % n];
        pieces.extend(segs.into_iter().map(|s| (l, s)));
    }
    // Step 4: neighbouring pieces of one cluster (adjacent rays, across
    // breakpoints too) whose trimmed convex hull keeps out of the free space
    // of every ray of their sectors become one piece.
    let point = |u: usize| rays[u % n];
    let mut cur: Option<(Option<usize>, Piece)> = None;
    for (l, next) in pieces {
        let Some((lc, c)) = cur.take() else {
            cur = Some((l, next));
            continue;
        };
        let merged = (lc == l && next.first <= c.last + 1)
            .then(|| merge_pieces(&ctx, &c, &next, point))
            .flatten();
        match merged {
            Some(m) => cur = Some((l, m)),
            None => {
                out.push(c.poly);
                cur = Some((l, next));
            }
        }
    }
    out.extend(cur.map(|(_, c)| c.poly));
    out
}

/// A convex piece, the unwrapped ray indices of its sector, and for each of
/// those rays the normal (away from the sensor) of the segment piece it came
/// from.
struct Piece {
    first: usize,
    last: usize,
    poly: Polygon,
    normals: Vec<Vector2<f64>>,
}

/// The convex hull of two neighbouring pieces of one chain (`b` after `a`),
/// trimmed where it enters seen free space, if it is a valid piece.
///
/// For every ray of the joint sector whose free part (along its direction,
/// to its range `range(u)` minus the free-space tolerance) enters the hull,
/// the hull is cut by the line through that free part's end, parallel to the
/// ray's own segment (its normal `w` has `w . d > 0`, so the whole free part
/// lies on the cut-away side). The merge is refused when a ray entered deeper
/// than `line_tolerance` (the hull bridges a concave corner: the pieces stay
/// apart), when a hit point (`point(u)`, m) ends up farther than 1 mm more
/// from the merged piece than from its own piece, when the sector is wider
/// than [`MAX_SECTOR`], or when the result has more than `max_vertices`
/// vertices. Rays outside the sector never enter: the hull lies inside the
/// sector.
fn merge_pieces(
    ctx: &PieceContext<'_>,
    a: &Piece,
    b: &Piece,
    point: impl Fn(usize) -> Option<Vector2<f64>>,
) -> Option<Piece> {
    let range = |u: usize| point(u).map_or(0.0, |q| (q - ctx.origin).norm());
    let (first, last) = (a.first, b.last.max(a.last));
    let n = ctx.rays;
    let h = (0.5 * core::f64::consts::TAU / n as f64).min(0.25);
    let span = ray_angle(ctx.heading, last, n) - ray_angle(ctx.heading, first, n) + 2.0 * h;
    if span > MAX_SECTOR || b.first < a.first {
        return None;
    }
    let normals: Vec<Vector2<f64>> = (first..=last)
        .map(|u| {
            if u <= a.last {
                a.normals[u - a.first]
            } else {
                b.normals[u - b.first]
            }
        })
        .collect();
    let pts: Vec<Vector2<f64>> = a
        .poly
        .vertices()
        .iter()
        .chain(b.poly.vertices())
        .copied()
        .collect();
    let mut hull = hull_of(&pts);
    for u in first..=last {
        let d = ray_direction(ctx.heading, u, n);
        let free = range(u) - ctx.tol;
        if free <= 0.0 {
            continue;
        }
        let Some(t_in) = ray_entry(&hull, ctx.origin, d, free) else {
            continue;
        };
        if free - t_in > ctx.params.line_tolerance {
            return None;
        }
        let w = normals[u - first];
        let e = ctx.origin + d * free;
        hull = clip_half_plane(&hull, w, w.dot(&e));
        if hull.len() < 3 {
            return None;
        }
    }
    if hull.len() > ctx.params.max_vertices.min(MAX_VERTICES) {
        return None;
    }
    // Cuts only shrink the hull; check every ray once more all the same.
    for u in first..=last {
        let free = range(u) - ctx.tol;
        if free > 0.0
            && ray_entry(&hull, ctx.origin, ray_direction(ctx.heading, u, n), free).is_some()
        {
            return None;
        }
    }
    let arr: Vec<[f64; 2]> = hull.iter().map(|p| [p.x, p.y]).collect();
    let poly = Polygon::new(&arr).ok()?;
    // The cuts must not lose points: each hit stays as near to the merged
    // piece as it was to its own (up to 1 mm).
    let dist = |q: &Polygon, p: &Vector2<f64>| closest_point_point_polygon(p, q).signed_distance;
    for u in first..=last {
        if let Some(p) = point(u) {
            let own = dist(&a.poly, &p).min(dist(&b.poly, &p));
            if dist(&poly, &p) > own.max(0.0) + 1e-3 {
                return None;
            }
        }
    }
    Some(Piece {
        first,
        last,
        poly,
        normals,
    })
}

/// The part of the CCW convex polygon `h` where `w . x >= c`
/// (Sutherland-Hodgman against one line), CCW.
fn clip_half_plane(h: &[Vector2<f64>], w: Vector2<f64>, c: f64) -> Vec<Vector2<f64>> {
    let mut out = Vec::with_capacity(h.len() + 1);
    for i in 0..h.len() {
        let (p, q) = (h[i], h[(i + 1) % h.len()]);
        let (fp, fq) = (w.dot(&p) - c, w.dot(&q) - c);
        if fp >= 0.0 {
            out.push(p);
        }
        if (fp >= 0.0) != (fq >= 0.0) {
            out.push(p + (q - p) * (fp / (fp - fq)));
        }
    }
    hull_of(&out)
}

/// Where the segment from `o` along the unit direction `d` to length `len`
/// (m) first gets more than 1e-10 m into the interior of the CCW convex
/// polygon `h`, if it does: the distance from `o` (Cyrus-Beck clipping).
fn ray_entry(h: &[Vector2<f64>], o: Vector2<f64>, d: Vector2<f64>, len: f64) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, len);
    for i in 0..h.len() {
        let (p, q) = (h[i], h[(i + 1) % h.len()]);
        let e = (q - p).normalize();
        let nrm = Vector2::new(-e.y, e.x); // inward for CCW
        let f0 = nrm.dot(&(o - p)) - 1e-10;
        let fd = nrm.dot(&d);
        if fd.abs() < 1e-15 {
            if f0 <= 0.0 {
                return None;
            }
            continue;
        }
        let t = -f0 / fd;
        if fd > 0.0 {
            t0 = t0.max(t);
        } else {
            t1 = t1.min(t);
        }
        if t0 >= t1 {
            return None;
        }
    }
    Some(t0)
}

/// The chains of consecutive rays of a scan (step 1 of the module docs of
/// [`super`]): `rays[k]` is ray `k`'s hit point (m, from `origin`, the rays
/// evenly spread over 360 degrees) or `None`; `group(k)` is ray `k`'s group
/// (its DBSCAN cluster), `None` for a ray in no chain. Two consecutive rays
/// are linked when both have a hit, they share a group, and (with `n >= 3`
/// rays and the detector's angle `lambda` above one ray's) their hits are at
/// most `r sin(dphi) / sin(lambda - dphi) + 3 sqrt(2) noise_sigma` apart (the
/// adaptive breakpoint detector, `r` the first hit's range). Each chain is a
/// run of linked rays as unwrapped ray indices `u` (ray `u % n`), starting
/// where a chain starts so that none wraps past the end of the scan.
pub(super) fn breakpoint_chains(
    rays: &[Option<Vector2<f64>>],
    origin: Vector2<f64>,
    params: &LidarParams,
    group: impl Fn(usize) -> Option<usize>,
) -> Vec<Vec<usize>> {
    let n = rays.len();
    if n == 0 {
        return Vec::new();
    }
    let dphi = core::f64::consts::TAU / n as f64;
    let lambda = params.breakpoint_angle;
    let linked = |a: usize, b: usize| -> bool {
        let (Some(la), Some(lb)) = (group(a), group(b)) else {
            return false;
        };
        let (Some(pa), Some(pb)) = (rays[a], rays[b]) else {
            return false;
        };
        if la != lb {
            return false;
        }
        if lambda <= dphi || n < 3 {
            return true;
        }
        let ra = (pa - origin).norm();
        let dmax = ra * dphi.sin() / (lambda - dphi).sin()
            + 3.0 * core::f64::consts::SQRT_2 * params.noise_sigma;
        (pb - pa).norm() <= dmax
    };
    // Start where a chain starts (a ray not linked to its predecessor), so
    // that no chain wraps past the end of the scan; 0 if all are linked.
    let start = (0..n).find(|&i| !linked((i + n - 1) % n, i)).unwrap_or(0);
    let mut chains: Vec<Vec<usize>> = Vec::new();
    let mut cur: Vec<usize> = Vec::new();
    for u in start..start + n {
        let i = u % n;
        if group(i).is_none() {
            if !cur.is_empty() {
                chains.push(std::mem::take(&mut cur));
            }
            continue;
        }
        if let Some(&last) = cur.last()
            && !linked(last % n, i)
        {
            chains.push(std::mem::take(&mut cur));
        }
        cur.push(u);
    }
    if !cur.is_empty() {
        chains.push(cur);
    }
    chains
}

/// How far short of its hit a ray is taken as seen free, m:
/// `3 noise_sigma + free_margin`.
pub fn free_tolerance(params: &LidarParams) -> f64 {
    3.0 * params.noise_sigma + params.free_margin
}

/// Split and merge (Iterative End Point Fit) of an ordered point chain: the
/// segments as inclusive index ranges `(a, b)` into `points`, in order,
/// neighbours sharing their end point. See the module docs.
pub fn split_and_merge(points: &[Vector2<f64>], tolerance: f64) -> Vec<(usize, usize)> {
    if points.is_empty() {
        return Vec::new();
    }
    // Split.
    let mut done: Vec<(usize, usize)> = Vec::new();
    let mut stack = vec![(0usize, points.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        let far = (a + 1..b)
            .map(|k| (k, chord_distance(points[a], points[b], points[k])))
            .max_by(|x, y| x.1.total_cmp(&y.1));
        match far {
            Some((k, d)) if d > tolerance => {
                stack.push((k, b)); // popped after (a, k): order kept
                stack.push((a, k));
            }
            _ => done.push((a, b)),
        }
    }
    // Merge neighbours whose union still fits one line.
    let mut merged: Vec<(usize, usize)> = Vec::with_capacity(done.len());
    for (a, b) in done {
        if let Some(last) = merged.last_mut()
            && line_fit(&points[last.0..=b]).2 <= tolerance
        {
            last.1 = b;
            continue;
        }
        merged.push((a, b));
    }
    merged
}

/// Distance of `p` from the line through `a` and `b` (from `a` when they
/// coincide), m.
fn chord_distance(a: Vector2<f64>, b: Vector2<f64>, p: Vector2<f64>) -> f64 {
    let e = b - a;
    let l = e.norm();
    if l < 1e-12 {
        return (p - a).norm();
    }
    (e.x * (p - a).y - e.y * (p - a).x).abs() / l
}

/// Total-least-squares line of `points` (>= 1): centroid, unit direction and
/// the largest distance of a point from the line (m). One point: direction x.
fn line_fit(points: &[Vector2<f64>]) -> (Vector2<f64>, Vector2<f64>, f64) {
    let m = points.len() as f64;
    let c = points.iter().fold(Vector2::zeros(), |s, p| s + p) / m;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let d = p - c;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let th = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let u = Vector2::new(th.cos(), th.sin());
    let res = points
        .iter()
        .map(|p| (u.x * (p - c).y - u.y * (p - c).x).abs())
        .fold(0.0, f64::max);
    (c, u, res)
}

/// What [`segment_piece`] needs besides the segment.
struct PieceContext<'a> {
    origin: Vector2<f64>,
    heading: f64,
    rays: usize,
    tol: f64,
    params: &'a LidarParams,
}

/// Smallest cosine between the piece's line normal and a ray of its sector.
const MIN_NORMAL_COS: f64 = 0.1;

/// Largest angular width of a piece's sector, rad.
const MAX_SECTOR: f64 = 0.8 * core::f64::consts::PI;

/// The piece of one segment (module docs, step 3), pushed to `out`: the
/// segment covers the unwrapped ray indices `idx` with hit points `pts` (same
/// length, >= 1). Halved (recursively) when its sector is too wide or too
/// oblique to its fitted line.
fn segment_piece(
    ctx: &PieceContext<'_>,
    idx: &[usize],
    pts: &[Vector2<f64>],
    out: &mut Vec<Piece>,
) {
    let o = ctx.origin;
    let n = ctx.rays;
    let dphi = core::f64::consts::TAU / n as f64;
    let h = (0.5 * dphi).min(0.25);
    let (first, last) = (idx[0], idx[idx.len() - 1]);
    let (tl, tr) = (
        ray_angle(ctx.heading, first, n) - h,
        ray_angle(ctx.heading, last, n) + h,
    );
    let (bl, br) = (
        Vector2::new(tl.cos(), tl.sin()),
        Vector2::new(tr.cos(), tr.sin()),
    );
    // The normal: of the fitted line (2+ points), else along the ray.
    let mut w = if pts.len() >= 2 {
        let (_, u, _) = line_fit(pts);
        Vector2::new(-u.y, u.x)
    } else {
        ray_direction(ctx.heading, first, n)
    };
    let mid = pts.iter().fold(Vector2::zeros(), |s, p| s + p) / pts.len() as f64 - o;
    if w.dot(&mid) < 0.0 {
        w = -w;
    }
    let ok = tr - tl <= MAX_SECTOR && w.dot(&bl) >= MIN_NORMAL_COS && w.dot(&br) >= MIN_NORMAL_COS;
    if !ok {
        if pts.len() >= 2 {
            let k = pts.len() / 2;
            segment_piece(ctx, &idx[..k], &pts[..k], out);
            segment_piece(ctx, &idx[k..], &pts[k..], out);
        }
        // A single ray always passes: w is its direction, the sector is
        // at most 0.5 rad wide.
        return;
    }
    // Near line: no seen-free ray part of the sector (its own rays, along
    // their directions, to their ranges minus `tol`) crosses it.
    let mut near = 1e-3f64;
    for (&j, p) in idx.iter().zip(pts) {
        let r = (p - o).norm();
        near = near.max(w.dot(&ray_direction(ctx.heading, j, n)) * (r - ctx.tol));
    }
    let far = pts.iter().map(|p| w.dot(&(p - o))).fold(near, f64::max) + ctx.params.min_thickness;
    let at = |b: Vector2<f64>, c: f64| o + b * (c / w.dot(&b));
    let quad = [at(bl, near), at(br, near), at(br, far), at(bl, far)];
    let arr: Vec<[f64; 2]> = quad.iter().map(|p| [p.x, p.y]).collect();
    // The quadrilateral has positive area (near < far, tl < tr); a sliver
    // below the polygon tolerances (a sector of nanometres) is dropped.
    if let Ok(p) = Polygon::new(&arr) {
        out.push(Piece {
            first,
            last,
            poly: p,
            normals: vec![w; last - first + 1],
        });
    }
}

/// `(a - o) x (b - o)`, m^2.
fn cross3(o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
}

/// The convex hull of `points` ([`convex_hull_into`]: counter-clockwise from
/// the lowest-x point, without collinear or repeated points; fewer than 3
/// points for degenerate sets), as a new vector.
pub(super) fn hull_of(points: &[Vector2<f64>]) -> Vec<Vector2<f64>> {
    let mut scratch = points.to_vec();
    let mut out = vec![Vector2::zeros(); 2 * points.len()];
    let n = convex_hull_into(&mut scratch, &mut out).expect("2 n slots hold the chain");
    out.truncate(n);
    out
}

/// Whether a convex polygon (CCW, >= 3 vertices) is at least `t` thick: its
/// width (the smallest extent across any of its edges, m) is `>= t`. Each
/// edge needs one vertex at least `t` from its line; the search starts at
/// the last edge's witness, which moves on around the polygon with the edges
/// (about two vertices an edge instead of all of them: a LiDAR ring of
/// thousands of points gives a hull of thousands of vertices).
pub(super) fn at_least_thick(h: &[Vector2<f64>], t: f64) -> bool {
    if t.is_nan() {
        return false;
    }
    if t <= 0.0 {
        return true;
    }
    let n = h.len();
    let mut witness = 0;
    for i in 0..n {
        let (a, b) = (h[i], h[(i + 1) % n]);
        let e = (b - a).normalize();
        let Some(k) = (0..n)
            .map(|s| (witness + s) % n)
            .find(|&k| (h[k] - a).x * -e.y + (h[k] - a).y * e.x >= t)
        else {
            return false;
        };
        witness = k;
    }
    true
}

/// Conservative simplification of a CCW convex polygon to at most `max`
/// vertices: repeatedly remove the edge whose two neighbours, extended, meet
/// with the smallest added triangle (ties: the edge that starts at the
/// earliest vertex of `hull`). The result contains the input.
///
/// O(n log n) for `n` hull vertices: the collapses wait in a heap and only
/// the four edges around a removed one are recomputed (a LiDAR ring of
/// thousands of points gives a hull of thousands of vertices; the scan of
/// every edge per removal took a third of a second there, docs/ros2.md).
pub fn simplify_outer(hull: &[Vector2<f64>], max: usize) -> Vec<Vector2<f64>> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    let n = hull.len();
    let target = max.max(3);
    if n <= target {
        return hull.to_vec();
    }
    let mut p = hull.to_vec();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut alive = vec![true; n];
    // The version of each vertex's edge: a heap entry of an older one is stale.
    let mut version = vec![0u32; n];
    let mut heap = BinaryHeap::new();
    let collapse = |p: &[Vector2<f64>], next: &[usize], prev: &[usize], i: usize| {
        let (i0, i2) = (prev[i], next[i]);
        collapse_edge(p[i0], p[i], p[i2], p[next[i2]])
    };
    for i in 0..n {
        if let Some((area, q)) = collapse(&p, &next, &prev, i) {
            heap.push(Reverse(Collapse {
                area,
                i,
                version: 0,
                q,
            }));
        }
    }
    let mut len = n;
    while len > target {
        let Some(Reverse(c)) = heap.pop() else {
            break;
        };
        if !alive[c.i] || version[c.i] != c.version {
            continue;
        }
        // Edge (i, j) collapses to the point q.
        let (i, j) = (c.i, next[c.i]);
        p[i] = c.q;
        let k = next[j];
        next[i] = k;
        prev[k] = i;
        alive[j] = false;
        len -= 1;
        for e in [prev[prev[i]], prev[i], i, k] {
            version[e] += 1;
            if let Some((area, q)) = collapse(&p, &next, &prev, e) {
                heap.push(Reverse(Collapse {
                    area,
                    i: e,
                    version: version[e],
                    q,
                }));
            }
        }
    }
    (0..n).filter(|&i| alive[i]).map(|i| p[i]).collect()
}

/// Where the edge `(p1, p2)` collapses when its neighbours `(p0, p1)` and
/// `(p2, p3)` are extended: their meeting point `q` and the area of the
/// triangle `p1 q p2` it adds; `None` when the extensions do not meet ahead
/// (a turn of pi or more).
pub(super) fn collapse_edge(
    p0: Vector2<f64>,
    p1: Vector2<f64>,
    p2: Vector2<f64>,
    p3: Vector2<f64>,
) -> Option<(f64, Vector2<f64>)> {
    let (d1, d2) = (p1 - p0, p3 - p2);
    let den = d1.x * d2.y - d1.y * d2.x;
    if den <= 1e-15 {
        return None;
    }
    let w = p2 - p1;
    let t = (w.x * d2.y - w.y * d2.x) / den;
    if t < 0.0 {
        return None;
    }
    let q = p1 + d1 * t;
    Some((0.5 * cross3(p1, q, p2).abs(), q))
}

/// A pending collapse of the edge that starts at vertex `i` (heap order:
/// the smallest area, then the earliest vertex).
struct Collapse {
    area: f64,
    i: usize,
    version: u32,
    q: Vector2<f64>,
}

impl PartialEq for Collapse {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == std::cmp::Ordering::Equal
    }
}

impl Eq for Collapse {}

impl PartialOrd for Collapse {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Collapse {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.area
            .total_cmp(&other.area)
            .then(self.i.cmp(&other.i))
            .then(self.version.cmp(&other.version))
    }
}

/// The thin-obstacle rectangle of a point set: aligned with its longest chord
/// (x axis for a single point), containing every point with `thickness / 2` to
/// spare on every side.
fn thin_rectangle(points: &[Vector2<f64>], thickness: f64) -> Vec<Vector2<f64>> {
    let mut u = Vector2::new(1.0, 0.0);
    let mut best = 0.0;
    for (i, a) in points.iter().enumerate() {
        for b in &points[i + 1..] {
            let d = (b - a).norm();
            if d > best {
                best = d;
                u = (b - a) / d;
            }
        }
    }
    let w = Vector2::new(-u.y, u.x);
    let (mut l0, mut l1, mut w0, mut w1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in points {
        let (a, b) = (p.dot(&u), p.dot(&w));
        l0 = l0.min(a);
        l1 = l1.max(a);
        w0 = w0.min(b);
        w1 = w1.max(b);
    }
    let m = 0.5 * thickness;
    let (l0, l1, w0, w1) = (l0 - m, l1 + m, w0 - m, w1 + m);
    vec![
        u * l0 + w * w0,
        u * l1 + w * w0,
        u * l1 + w * w1,
        u * l0 + w * w1,
    ]
}

/// The obstacle inferred from one cluster (see the module docs): a valid convex
/// polygon that contains every point of the cluster. `points` must be non-empty
/// and finite.
pub fn cluster_polygon(
    points: &[Vector2<f64>],
    min_thickness: f64,
    max_vertices: usize,
) -> Polygon {
    let to_arr = |v: &[Vector2<f64>]| v.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>();
    let hull = hull_of(points);
    if hull.len() >= 3 && at_least_thick(&hull, min_thickness) {
        let h = simplify_outer(&hull, max_vertices.clamp(4, MAX_VERTICES));
        if let Ok(p) = Polygon::new(&to_arr(&h)) {
            return p;
        }
    }
    let rect = thin_rectangle(points, min_thickness);
    Polygon::new(&to_arr(&rect)).expect("a rectangle with positive sides is a convex polygon")
}
