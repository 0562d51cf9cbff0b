//! The convex hull of a point set: Andrew's monotone chain, without
//! allocation, over points sorted in a caller's buffer ([`convex_hull_into`])
//! or visited in order by selection ([`super::ConvexPolygon::hull`]).

use core::cmp::Ordering;

use nalgebra::Vector2;

use super::{GeometryError, norm};

/// Two points of a set closer than this (m) are one point for the convex hull
/// ([`convex_hull_into`]; each point, in sorted order, against the last one kept).
pub const HULL_MERGE_TOL: f64 = 1e-12;

/// `(a - o) x (b - o)`: positive when `o -> a -> b` turns left.
fn cross3(o: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
}

/// The (x, y) order of points (`total_cmp`: every point has its place).
fn xy_order(a: &Vector2<f64>, b: &Vector2<f64>) -> Ordering {
    a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y))
}

/// Andrew's monotone chain over distinct points given in ascending (x, y)
/// order by `ascending` and in descending order by `descending` (at least 3 of
/// them for a hull; fewer give fewer than 3 points): the lower chain, then the
/// upper one, each dropping the points that do not turn left (collinear ones
/// too), into `chain`. Returns the number of hull vertices, counter-clockwise
/// from the first point. [`GeometryError::TooManyVertices`] when `chain` is full.
pub(super) fn monotone_chain(
    ascending: impl Iterator<Item = Vector2<f64>>,
    descending: impl Iterator<Item = Vector2<f64>>,
    chain: &mut [Vector2<f64>],
) -> Result<usize, GeometryError> {
    let mut len = 0usize;
    half_chain(ascending, chain, &mut len)?;
    half_chain(descending, chain, &mut len)?;
    Ok(len)
}

/// One pass of [`monotone_chain`], appended to `chain[..len]`. The pass's last
/// point starts the other chain: it is dropped at the end.
fn half_chain(
    points: impl Iterator<Item = Vector2<f64>>,
    chain: &mut [Vector2<f64>],
    len: &mut usize,
) -> Result<(), GeometryError> {
    let start = *len;
    for q in points {
        while *len >= start + 2 {
            let (Some(a), Some(b)) = (chain.get(*len - 2), chain.get(*len - 1)) else {
                break;
            };
            if cross3(a, b, &q) > 0.0 {
                break;
            }
            *len -= 1;
        }
        *chain.get_mut(*len).ok_or(GeometryError::TooManyVertices)? = q;
        *len += 1;
    }
    *len = len.saturating_sub(1).max(start);
    Ok(())
}

/// The position of a point in the (x, y) order of [`xy_order`] (`total_cmp`'s
/// order, as integers).
#[inline(never)]
fn order_key(v: &Vector2<f64>) -> (i64, i64) {
    let key = |f: f64| {
        let bits = f.to_bits() as i64;
        bits ^ (((bits >> 63) as u64) >> 1) as i64
    };
    (key(v.x), key(v.y))
}

/// The distinct points of a list in ascending or descending (x, y) order, each
/// found by a pass over the list (no buffer to sort in). A point within
/// [`HULL_MERGE_TOL`] of the last one given is skipped.
#[derive(Clone)]
pub(super) struct Selection<'a> {
    points: &'a [[f64; 2]],
    ascending: bool,
    /// The order key of the last point passed (given or skipped).
    last: Option<(i64, i64)>,
    /// The last point given.
    kept: Option<Vector2<f64>>,
}

impl<'a> Selection<'a> {
    pub(super) fn new(points: &'a [[f64; 2]], ascending: bool) -> Self {
        Selection {
            points,
            ascending,
            last: None,
            kept: None,
        }
    }
}

impl Iterator for Selection<'_> {
    type Item = Vector2<f64>;

    fn next(&mut self) -> Option<Vector2<f64>> {
        // `a` strictly before `b` in the direction of travel.
        let before = |a: (i64, i64), b: (i64, i64)| a != b && (a < b) == self.ascending;
        loop {
            let mut next: Option<((i64, i64), Vector2<f64>)> = None;
            for p in self.points {
                let v = Vector2::new(p[0], p[1]);
                let k = order_key(&v);
                if self.last.is_none_or(|l| before(l, k)) && next.is_none_or(|(n, _)| before(k, n))
                {
                    next = Some((k, v));
                }
            }
            let (k, v) = next?;
            self.last = Some(k);
            if self.kept.is_some_and(|q| norm(&(v - q)) <= HULL_MERGE_TOL) {
                continue;
            }
            self.kept = Some(v);
            return Some(v);
        }
    }
}

/// The convex hull of a point set (Andrew's monotone chain), counter-clockwise
/// from its lowest-x (then lowest-y) point, without collinear or repeated
/// points: the one hull of the workspace
/// ([`ConvexPolygon::hull`](super::ConvexPolygon::hull) and the simulator's
/// LiDAR obstacles use it). No allocation: `points` is the
/// caller's scratch, sorted by (x, y) and cleared of duplicates in place (a
/// point within [`HULL_MERGE_TOL`] of the last one kept is dropped); the hull
/// goes to `out`, and the number of its vertices is returned. Fewer than 3
/// distinct points (one, two, or none) are returned as they are, sorted; three
/// or more collinear ones give their two ends.
///
/// `out` needs room for the chain while it runs: `2 * points.len()` always
/// suffices; [`GeometryError::TooManyVertices`] when it is full. The points
/// are not checked (a NaN coordinate gives a meaningless hull, not a panic).
pub fn convex_hull_into(
    points: &mut [Vector2<f64>],
    out: &mut [Vector2<f64>],
) -> Result<usize, GeometryError> {
    points.sort_unstable_by(xy_order);
    let mut kept = 0usize;
    for i in 0..points.len() {
        let Some(&p) = points.get(i) else {
            break;
        };
        let last = kept.checked_sub(1).and_then(|l| points.get(l));
        if last.is_some_and(|l| norm(&(p - l)) <= HULL_MERGE_TOL) {
            continue;
        }
        if let Some(slot) = points.get_mut(kept) {
            *slot = p;
        }
        kept += 1;
    }
    let sorted = points.get(..kept).unwrap_or_default();
    if sorted.len() < 3 {
        for (i, p) in sorted.iter().enumerate() {
            *out.get_mut(i).ok_or(GeometryError::TooManyVertices)? = *p;
        }
        return Ok(sorted.len());
    }
    monotone_chain(sorted.iter().copied(), sorted.iter().rev().copied(), out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ConvexPolygon;

    type Poly = ConvexPolygon<8>;
    const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    /// `convex_hull_into` of `pts` into a buffer of `2 n` (the hull's points).
    fn chain_hull(pts: &[[f64; 2]]) -> ([Vector2<f64>; 64], usize) {
        let mut scratch = [Vector2::zeros(); 32];
        for (s, p) in scratch.iter_mut().zip(pts) {
            *s = v(p[0], p[1]);
        }
        let mut out = [Vector2::zeros(); 64];
        let n = convex_hull_into(&mut scratch[..pts.len()], &mut out[..2 * pts.len()]).unwrap();
        (out, n)
    }

    #[test]
    fn convex_hull_into_keeps_corners_only() {
        // Interior, collinear, repeated and nearly repeated points are dropped;
        // counter-clockwise from the lowest-x (then lowest-y) point.
        let pts = [
            [0.5, 0.5],
            [1.0, 1.0],
            [0.5, 0.0],
            [0.0, 1.0],
            [1.0, 0.0],
            [0.0, 0.0],
            [1.0, 1.0],
            [1.0 + 1e-13, 1.0],
            [0.2, 0.7],
        ];
        let (h, n) = chain_hull(&pts);
        assert_eq!(h[..n], [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]);
        // Degenerate sets: their distinct points, sorted; collinear: the ends.
        let (h, n) = chain_hull(&[[2.0, 2.0], [0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]);
        assert_eq!(h[..n], [v(0.0, 0.0), v(2.0, 2.0)]);
        let (h, n) = chain_hull(&[[3.0, 1.0], [3.0, 1.0]]);
        assert_eq!(h[..n], [v(3.0, 1.0)]);
        let (h, n) = chain_hull(&[[1.0, 0.0], [0.0, 5.0]]);
        assert_eq!(h[..n], [v(0.0, 5.0), v(1.0, 0.0)]);
        assert_eq!(chain_hull(&[]).1, 0);
        // An output too short for the chain is an error, not a panic.
        let mut pts = [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)];
        let mut out = [Vector2::zeros(); 3];
        assert_eq!(
            convex_hull_into(&mut pts, &mut out),
            Err(GeometryError::TooManyVertices)
        );
    }

    #[test]
    fn polygon_hull_is_the_chain_from_the_lowest_corner() {
        // A diamond: the chain starts at the leftmost point, the polygon at the
        // lowest one.
        let diamond = [[0.0, 1.0], [1.0, 0.0], [2.0, 1.0], [1.0, 2.0]];
        let (h, _) = chain_hull(&diamond);
        assert_eq!(h[0], v(0.0, 1.0));
        let p = Poly::hull(&diamond).unwrap();
        assert_eq!(
            p.vertices(),
            [v(1.0, 0.0), v(2.0, 1.0), v(1.0, 2.0), v(0.0, 1.0)]
        );
        // Random point sets: the same corners, rotated to the lowest one.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut unif = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for n in (3..30).cycle().take(300) {
            let pts: [[f64; 2]; 32] = core::array::from_fn(|_| [unif() * 4.0, unif() * 3.0]);
            let (h, len) = chain_hull(&pts[..n]);
            let p = ConvexPolygon::<32>::hull(&pts[..n]).unwrap();
            assert_eq!(p.len(), len);
            let s = (0..len).find(|&i| h[i] == p.vertices()[0]).unwrap();
            for (k, q) in p.vertices().iter().enumerate() {
                assert_eq!(*q, h[(s + k) % len]);
            }
        }
        // Many points, few corners: the chain stays within its buffer.
        let mut many = [[0.0; 2]; 400];
        for (i, p) in many.iter_mut().enumerate() {
            *p = [0.05 + 0.9 * unif(), 0.05 + 0.9 * unif()];
            if i < 4 {
                *p = SQUARE[i];
            }
        }
        assert_eq!(Poly::hull(&many), Ok(Poly::new(&SQUARE).unwrap()));
    }

    #[test]
    fn polygon_hull_holds_every_point_of_a_decimal_grid() {
        // Points on a 0.1 m grid (decimal steps: near-collinear in binary).
        // The former gift wrapping returned `NotConvex` for the first set and
        // left (1.9, 0.6) 0.23 m and (1.7, 0.5) 0.17 m outside the hull of the
        // second.
        let t = |v: f64| v * 0.1;
        let sets: [&[[f64; 2]]; 2] = [
            &[
                [18.0, 1.0],
                [5.0, 13.0],
                [18.0, 18.0],
                [6.0, 15.0],
                [10.0, 1.0],
                [9.0, 1.0],
                [2.0, 10.0],
                [7.0, 1.0],
                [8.0, 0.0],
                [10.0, 18.0],
                [15.0, 2.0],
                [17.0, 17.0],
                [10.0, 14.0],
                [8.0, 14.0],
                [4.0, 15.0],
                [3.0, 18.0],
                [14.0, 5.0],
                [1.0, 15.0],
                [2.0, 16.0],
                [12.0, 12.0],
                [5.0, 9.0],
                [11.0, 0.0],
                [2.0, 6.0],
                [0.0, 11.0],
                [7.0, 3.0],
                [12.0, 19.0],
                [14.0, 8.0],
                [18.0, 3.0],
                [8.0, 5.0],
            ],
            &[
                [10.0, 16.0],
                [14.0, 7.0],
                [9.0, 18.0],
                [8.0, 13.0],
                [11.0, 13.0],
                [9.0, 5.0],
                [2.0, 7.0],
                [19.0, 6.0],
                [12.0, 14.0],
                [12.0, 19.0],
                [8.0, 13.0],
                [17.0, 5.0],
                [18.0, 15.0],
                [8.0, 9.0],
                [6.0, 19.0],
                [11.0, 14.0],
                [6.0, 9.0],
                [5.0, 5.0],
                [2.0, 19.0],
                [7.0, 1.0],
                [4.0, 7.0],
                [3.0, 6.0],
                [4.0, 8.0],
                [6.0, 16.0],
                [2.0, 1.0],
                [11.0, 9.0],
                [18.0, 13.0],
                [4.0, 1.0],
                [7.0, 12.0],
                [3.0, 17.0],
                [15.0, 6.0],
                [4.0, 4.0],
                [19.0, 9.0],
                [15.0, 12.0],
                [12.0, 3.0],
                [13.0, 12.0],
                [9.0, 7.0],
                [4.0, 2.0],
                [4.0, 2.0],
                [4.0, 15.0],
            ],
        ];
        for set in sets {
            // As the scenario files write them: 0.1 * k, rounded once.
            let mut buf = [[0.0; 2]; 40];
            for (b, p) in buf.iter_mut().zip(set) {
                *b = [t(p[0]), t(p[1])];
            }
            let pts = &buf[..set.len()];
            let poly = ConvexPolygon::<32>::hull(pts).unwrap();
            for p in pts {
                let d = crate::closest_point_point_polygon(&v(p[0], p[1]), &poly);
                assert!(
                    d.signed_distance <= 1e-9,
                    "{p:?} is {} m out",
                    d.signed_distance
                );
            }
        }
    }
}
