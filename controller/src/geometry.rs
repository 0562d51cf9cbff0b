//! Convex polygons (world frame, metres) and the closest-point query behind the
//! LDCBF half-planes (docs/maths.md §2.3).
//!
//! A [`ConvexPolygon`] can only be built through a validating constructor, so
//! every polygon the controller sees is finite, has at least three distinct
//! vertices, positive area, is strictly convex and is stored counter-clockwise
//! with duplicate and collinear vertices removed. Input may come in either order.

use nalgebra::Vector2;

mod hull;

pub use hull::{HULL_MERGE_TOL, convex_hull_into};
use hull::{Selection, monotone_chain};

/// Two vertices closer than this (m) are the same vertex.
pub const DUPLICATE_TOL: f64 = 1e-9;
/// A point closer than this (m) to the boundary is on the boundary.
pub const ON_BOUNDARY_TOL: f64 = 1e-9;
/// Largest absolute vertex coordinate accepted (m): 1000 km, far beyond any map,
/// small enough that squared distances stay exact to well under a millimetre.
pub const MAX_COORDINATE: f64 = 1e6;
/// Default vertex capacity of a polygon.
pub const DEFAULT_MAX_VERTICES: usize = 32;

/// Why a vertex list is not a valid convex polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryError {
    /// A coordinate is NaN or infinite.
    NotFinite,
    /// A coordinate exceeds [`MAX_COORDINATE`] in absolute value.
    OutOfRange,
    /// Fewer than three distinct vertices (points closer than [`DUPLICATE_TOL`]
    /// count once, wherever they are in the list).
    TooFewVertices,
    /// At least three distinct vertices, but all collinear (zero area).
    ZeroArea,
    /// The vertices do not form a convex polygon in the given order (a reflex
    /// vertex, a spike, or a self-intersecting outline).
    NotConvex,
    /// More vertices (after clean-up) than the capacity `V`.
    TooManyVertices,
}

impl core::fmt::Display for GeometryError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            GeometryError::NotFinite => "a vertex coordinate is not finite",
            GeometryError::OutOfRange => "a vertex coordinate exceeds 1e6 m in absolute value",
            GeometryError::TooFewVertices => "fewer than 3 distinct vertices",
            GeometryError::ZeroArea => "all vertices are collinear (zero area)",
            GeometryError::NotConvex => {
                "the vertices do not form a convex polygon (not convex or self-intersecting)"
            }
            GeometryError::TooManyVertices => "more vertices than the polygon capacity",
        })
    }
}

impl core::error::Error for GeometryError {}

/// A strictly convex polygon with at most `V` vertices, stored counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConvexPolygon<const V: usize = DEFAULT_MAX_VERTICES> {
    vertices: [Vector2<f64>; V],
    len: usize,
}

fn check_points(points: &[[f64; 2]]) -> Result<(), GeometryError> {
    for p in points {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err(GeometryError::NotFinite);
        }
        if p[0].abs() > MAX_COORDINATE || p[1].abs() > MAX_COORDINATE {
            return Err(GeometryError::OutOfRange);
        }
    }
    Ok(())
}

/// Euclidean length `|v|` (m): `sqrt(|v|^2)`, as nalgebra's `norm`, with the
/// controller's square root ([`crate::linalg::sqrt`]; one instruction on the
/// Cortex-M7).
fn norm(v: &Vector2<f64>) -> f64 {
    crate::linalg::sqrt(v.norm_squared())
}

/// The outward unit normal of the edge from `a` to `b` of a counter-clockwise
/// polygon.
fn outward_normal(a: &Vector2<f64>, b: &Vector2<f64>) -> Vector2<f64> {
    let e = b - a;
    Vector2::new(e.y, -e.x) / norm(&e)
}

fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// The error for a degenerate (zero-area) point set: [`GeometryError::NotConvex`]
/// when a point lies off the line of the first two distinct ones (the outline
/// crosses itself, as a bow-tie), else [`GeometryError::ZeroArea`] when it has
/// three distinct points, [`GeometryError::TooFewVertices`] otherwise.
fn degenerate(mut pts: impl Iterator<Item = Vector2<f64>> + Clone) -> GeometryError {
    let far = |p: &Vector2<f64>, q: &Vector2<f64>| norm(&(p - q)) > DUPLICATE_TOL;
    let Some(a) = pts.next() else {
        return GeometryError::TooFewVertices;
    };
    let Some(b) = pts.clone().find(|b| far(b, &a)) else {
        return GeometryError::TooFewVertices;
    };
    let mut three = false;
    for c in pts.filter(|c| far(c, &a) && far(c, &b)) {
        three = true;
        // A point off the line a-b: the outline has no net area because it
        // crosses itself (a bow-tie), not because the points are collinear.
        let (u, w) = (b - a, c - a);
        if cross(&u, &w).abs() > 1e-9 * norm(&u) * norm(&w) {
            return GeometryError::NotConvex;
        }
    }
    if three {
        GeometryError::ZeroArea
    } else {
        GeometryError::TooFewVertices
    }
}

/// `(v[i + s], v[i + s + 1], v[i + s + 2])` for `i = 0..v.len()`, indices modulo
/// `v.len()`: each vertex with its neighbours, cyclically, starting at `s`.
fn triples<T>(v: &[T], s: usize) -> impl Iterator<Item = (&T, &T, &T)> {
    let from = |k: usize| v.iter().cycle().skip(k);
    from(s)
        .zip(from(s + 1))
        .zip(from(s + 2))
        .take(v.len())
        .map(|((a, b), c)| (a, b, c))
}

/// `(v[i], v[(i + 1) % n])` for `i = 0..n`: the edges of a closed outline.
fn edges<T>(v: &[T]) -> impl Iterator<Item = (&T, &T)> {
    v.iter().zip(v.iter().skip(1).chain(v.first()))
}

impl<const V: usize> ConvexPolygon<V> {
    /// Validates a vertex list (either orientation) as a convex polygon.
    /// Consecutive duplicates and collinear vertices are removed first.
    pub fn new(points: &[[f64; 2]]) -> Result<Self, GeometryError> {
        const { assert!(V >= 3, "a polygon needs room for 3 vertices") };
        check_points(points)?;
        // 1. Drop consecutive duplicates (cyclically).
        let mut buf = [Vector2::zeros(); V];
        let mut n = 0usize;
        let mut last: Option<Vector2<f64>> = None;
        for p in points {
            let v = Vector2::new(p[0], p[1]);
            if last.is_some_and(|l| norm(&(v - l)) <= DUPLICATE_TOL) {
                continue;
            }
            let Some(slot) = buf.get_mut(n) else {
                return Err(GeometryError::TooManyVertices);
            };
            *slot = v;
            n += 1;
            last = Some(v);
        }
        let mut pts = &buf[..n.min(V)];
        while let Some((last, init)) = pts.split_last()
            && init
                .first()
                .is_some_and(|first| norm(&(last - first)) <= DUPLICATE_TOL)
        {
            pts = init;
        }
        let n = pts.len();
        let Some(&first) = pts.first() else {
            return Err(GeometryError::TooFewVertices);
        };
        if n < 3 {
            return Err(GeometryError::TooFewVertices);
        }
        // 2. Orientation from the signed area; zero area means collinear.
        let area2 = edges(pts).fold(0.0, |s, (a, b)| s + cross(a, b));
        let scale = pts.iter().fold(0.0f64, |m, v| m.max(v.amax()));
        let span = pts.iter().fold(0.0f64, |m, v| m.max(norm(&(v - first))));
        if area2.abs() <= 1e-12 * span * span.max(scale.max(1.0)) {
            return Err(degenerate(pts.iter().copied()));
        }
        let pts = &mut buf[..n.min(V)];
        if area2 < 0.0 {
            // Reverse in place; `<[T]>::reverse` keeps a bounds check the
            // optimiser cannot remove (see `nopanic/`).
            let (front, back) = pts.split_at_mut(n / 2);
            for (a, b) in front.iter_mut().zip(back.iter_mut().rev()) {
                core::mem::swap(a, b);
            }
        }
        // 3. Remove collinear vertices; reject reflex vertices and spikes.
        let mut out = [Vector2::zeros(); V];
        let mut len = 0usize;
        for (prev, cur, next) in triples(pts, n - 1) {
            let e1 = cur - prev;
            let e2 = next - cur;
            let c = cross(&e1, &e2);
            let tol = 1e-12 * norm(&e1) * norm(&e2);
            if c.abs() <= tol {
                if e1.dot(&e2) < 0.0 {
                    return Err(GeometryError::NotConvex); // spike
                }
                continue; // collinear: not a corner
            }
            if c < 0.0 {
                return Err(GeometryError::NotConvex);
            }
            // At most `n <= V` corners: the slot always exists.
            let Some(slot) = out.get_mut(len) else {
                return Err(GeometryError::TooManyVertices);
            };
            *slot = *cur;
            len += 1;
        }
        if len < 3 {
            return Err(degenerate(pts.iter().copied()));
        }
        // 4. All left turns could still wind twice (a pentagram): require the
        // exterior angles to add up to one turn.
        let mut turn = 0.0;
        for (a, b, c) in triples(&out[..len.min(V)], 0) {
            let e1 = b - a;
            let e2 = c - b;
            turn += libm::atan2(cross(&e1, &e2), e1.dot(&e2));
        }
        if (turn - 2.0 * core::f64::consts::PI).abs() > 1e-6 {
            return Err(GeometryError::NotConvex);
        }
        Ok(ConvexPolygon { vertices: out, len })
    }

    /// The convex hull of a point set ([`convex_hull_into`]'s monotone chain,
    /// at most `V` hull vertices), stored from its lowest (then leftmost)
    /// corner. Fails like [`ConvexPolygon::new`] when the hull has fewer than 3
    /// corners: [`GeometryError::TooFewVertices`] for one or two distinct points,
    /// [`GeometryError::ZeroArea`] for three or more collinear ones; with
    /// [`GeometryError::TooManyVertices`] when the hull has more than `V`
    /// corners (or, for a few point sets with many points, when the chain
    /// holds more than `2 V` points while it runs).
    ///
    /// Without a buffer to sort them in, the points are visited in order by
    /// selection: `O(n^2)` for `n` points, no allocation.
    pub fn hull(points: &[[f64; 2]]) -> Result<Self, GeometryError> {
        check_points(points)?;
        let points_v = || points.iter().map(|p| Vector2::new(p[0], p[1]));
        // The chain holds a little more than the hull while it runs.
        let mut buf = [[Vector2::zeros(); V]; 2];
        let chain = buf.as_flattened_mut();
        let len = monotone_chain(
            Selection::new(points, true),
            Selection::new(points, false),
            chain,
        )?;
        let found = chain.get(..len).unwrap_or_default();
        if found.len() < 3 {
            return Err(degenerate(points_v()));
        }
        if found.len() > V {
            return Err(GeometryError::TooManyVertices);
        }
        // Start at the lowest (then leftmost) corner.
        let lower = |a: &Vector2<f64>, b: &Vector2<f64>| a.y < b.y || (a.y == b.y && a.x < b.x);
        let start = found
            .iter()
            .enumerate()
            .reduce(|best, (i, a)| if lower(a, best.1) { (i, a) } else { best })
            .map_or(0, |(i, _)| i);
        let mut corners = [[0.0f64; 2]; V];
        for (k, slot) in corners.iter_mut().take(found.len()).enumerate() {
            if let Some(v) = found.get((start + k) % found.len()) {
                *slot = [v.x, v.y];
            }
        }
        match Self::new(&corners[..found.len().min(V)]) {
            // Judged on all the points, not only the corners found.
            Err(GeometryError::ZeroArea | GeometryError::TooFewVertices) => {
                Err(degenerate(points_v()))
            }
            other => other,
        }
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Vector2<f64>] {
        // `len <= V` by construction; the `min` lets the compiler see it.
        &self.vertices[..self.len.min(V)]
    }

    /// Number of vertices (>= 3).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false: a valid polygon has at least three vertices.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Whether `p` is inside or on the boundary (tolerance [`ON_BOUNDARY_TOL`]).
    pub fn contains(&self, p: &Vector2<f64>) -> bool {
        closest_point_point_polygon(p, self).signed_distance <= ON_BOUNDARY_TOL
    }

    /// The outward unit normals of the two edges that meet at the vertex at
    /// `c` (within [`DUPLICATE_TOL`]): the edge that ends there, then the one
    /// that starts there (the vertex's normal cone lies between them). `None`
    /// when `c` is not a vertex.
    pub(crate) fn edge_normals_at(&self, c: &Vector2<f64>) -> Option<(Vector2<f64>, Vector2<f64>)> {
        let verts = self.vertices();
        let n = verts.len();
        let k = verts
            .iter()
            .position(|v| (v - c).norm_squared() < DUPLICATE_TOL * DUPLICATE_TOL)?;
        let (prev, at, next) = (
            verts.get((k + n - 1) % n)?,
            verts.get(k)?,
            verts.get((k + 1) % n)?,
        );
        Some((outward_normal(prev, at), outward_normal(at, next)))
    }
}

/// Where the query point lies relative to the polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointLocation {
    /// Strictly outside (distance > [`ON_BOUNDARY_TOL`]).
    Outside,
    /// Within [`ON_BOUNDARY_TOL`] of the boundary.
    OnBoundary,
    /// Strictly inside.
    Inside,
}

/// Result of [`closest_point_point_polygon`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestPoint {
    /// `c`: the point of the boundary closest to the query point (m, world).
    pub point: Vector2<f64>,
    /// `eta`: unit normal of the LDCBF half-plane, pointing to the safe side:
    /// `(p - c)/|p - c|` outside, `(c - p)/|c - p|` inside, the outward edge normal
    /// on the boundary (at a vertex: the normalised sum of the two edge normals).
    pub normal: Vector2<f64>,
    /// Signed distance from the query point to the boundary (m): positive outside,
    /// negative inside, zero on the boundary.
    pub signed_distance: f64,
    /// Where the query point is.
    pub location: PointLocation,
}

/// Closest boundary point, safe-side normal and signed distance from `p` to `poly`.
/// Cost `O(V)`. `p` must be finite (the controller checks its inputs first); a
/// non-finite `p` gives a non-finite result, never a panic.
pub fn closest_point_point_polygon<const V: usize>(
    p: &Vector2<f64>,
    poly: &ConvexPolygon<V>,
) -> ClosestPoint {
    let verts = poly.vertices();
    let n = verts.len();
    // A polygon has at least three vertices; an empty one would be infinitely far.
    let Some(&first) = verts.first() else {
        return ClosestPoint {
            point: *p,
            normal: Vector2::zeros(),
            signed_distance: f64::INFINITY,
            location: PointLocation::Outside,
        };
    };
    let mut best_d2 = f64::INFINITY;
    let mut best_c = first;
    let mut best_edge = 0usize;
    let mut best_t = 0.0;
    let mut inside = true;
    // Edge `i` runs from vertex `i` (`a`) to vertex `i + 1` (`b`).
    let mut edge = |i: usize, a: Vector2<f64>, b: Vector2<f64>| {
        let ab = b - a;
        let ap = p - a;
        if cross(&ab, &ap) <= 0.0 {
            inside = false;
        }
        let t = (ap.dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
        let c = a + ab * t;
        let d2 = (p - c).norm_squared();
        if d2 < best_d2 {
            best_d2 = d2;
            best_c = c;
            best_edge = i;
            best_t = t;
        }
    };
    let mut a = first;
    for (i, &b) in verts.iter().enumerate().skip(1) {
        edge(i - 1, a, b);
        a = b;
    }
    edge(n - 1, a, first); // the closing edge
    let dist = crate::linalg::sqrt(best_d2);
    // Edge `i` runs from vertex `i` to vertex `i + 1` (indices modulo `n >= 1`;
    // both always exist, the zero vector is never used).
    let edge_normal = |i: usize| match (verts.get(i % n), verts.get((i + 1) % n)) {
        (Some(a), Some(b)) => outward_normal(a, b),
        _ => Vector2::zeros(),
    };
    if dist <= ON_BOUNDARY_TOL {
        let mut nrm = edge_normal(best_edge);
        if best_t <= 0.0 {
            nrm += edge_normal((best_edge + n - 1) % n);
        } else if best_t >= 1.0 {
            nrm += edge_normal((best_edge + 1) % n);
        }
        return ClosestPoint {
            point: best_c,
            normal: nrm / norm(&nrm),
            signed_distance: 0.0,
            location: PointLocation::OnBoundary,
        };
    }
    // Inside an edge (0 < t < 1) the normal is the edge's outward normal, exactly;
    // computing it as (p - c)/|p - c| would lose precision when p is within
    // nanometres of the edge. At a vertex (outside only) the direction to p is
    // the normal.
    let interior = best_t > 0.0 && best_t < 1.0;
    if inside {
        ClosestPoint {
            point: best_c,
            normal: if interior {
                edge_normal(best_edge)
            } else {
                (best_c - p) / dist
            },
            signed_distance: -dist,
            location: PointLocation::Inside,
        }
    } else {
        ClosestPoint {
            point: best_c,
            normal: if interior {
                edge_normal(best_edge)
            } else {
                (p - best_c) / dist
            },
            signed_distance: dist,
            location: PointLocation::Outside,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Poly = ConvexPolygon<8>;
    const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    #[test]
    fn either_orientation_is_stored_ccw() {
        let a = Poly::new(&SQUARE).unwrap();
        let mut rev = SQUARE;
        rev.reverse();
        let b = Poly::new(&rev).unwrap();
        assert_eq!(a.len(), 4);
        assert_eq!(b.len(), 4);
        for p in [&a, &b] {
            let vs = p.vertices();
            let mut area2 = 0.0;
            for i in 0..vs.len() {
                area2 += cross(&vs[i], &vs[(i + 1) % vs.len()]);
            }
            assert!((area2 - 2.0).abs() < 1e-15);
        }
    }

    #[test]
    fn duplicates_and_collinear_points_are_removed() {
        let p = Poly::new(&[
            [0.0, 0.0],
            [0.0, 0.0],
            [0.5, 0.0],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 1.0],
            [0.0, 0.0],
        ])
        .unwrap();
        assert_eq!(p.len(), 4);
    }

    #[test]
    fn invalid_inputs_are_typed_errors() {
        assert_eq!(Poly::new(&[]), Err(GeometryError::TooFewVertices));
        assert_eq!(
            Poly::new(&[[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]]),
            Err(GeometryError::TooFewVertices)
        );
        assert_eq!(
            Poly::new(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]),
            Err(GeometryError::ZeroArea)
        );
        assert_eq!(
            Poly::new(&[[0.0, 0.0], [1.0, f64::NAN], [2.0, 0.0]]),
            Err(GeometryError::NotFinite)
        );
        // Reflex vertex (an arrow head).
        assert_eq!(
            Poly::new(&[[0.0, 0.0], [2.0, 0.0], [1.0, 0.5], [2.0, 2.0], [0.0, 2.0]]),
            Err(GeometryError::NotConvex)
        );
        // Self-intersecting bow tie.
        assert_eq!(
            Poly::new(&[[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 1.0]]),
            Err(GeometryError::NotConvex)
        );
        // Pentagram: all turns the same way, but winds twice.
        let mut star = [[0.0; 2]; 5];
        for (i, s) in star.iter_mut().enumerate() {
            let a = (i as f64) * 4.0 * core::f64::consts::PI / 5.0;
            *s = [libm::cos(a), libm::sin(a)];
        }
        assert_eq!(Poly::new(&star), Err(GeometryError::NotConvex));
        assert_eq!(
            Poly::new(&[[0.0, 0.0], [2e6, 0.0], [0.0, 1.0]]),
            Err(GeometryError::OutOfRange)
        );
        let many = [[0.0, 0.0]; 9];
        assert_eq!(Poly::new(&many), Err(GeometryError::TooFewVertices));
        let mut circle = [[0.0; 2]; 9];
        for (i, s) in circle.iter_mut().enumerate() {
            let a = (i as f64) * 2.0 * core::f64::consts::PI / 9.0;
            *s = [libm::cos(a), libm::sin(a)];
        }
        assert_eq!(Poly::new(&circle), Err(GeometryError::TooManyVertices));
    }

    #[test]
    fn hull_of_scattered_points() {
        let pts = [
            [0.5, 0.5],
            [0.0, 0.0],
            [1.0, 0.0],
            [0.2, 0.7],
            [1.0, 1.0],
            [0.5, 0.0],
            [0.0, 1.0],
        ];
        let h = Poly::hull(&pts).unwrap();
        assert_eq!(h.len(), 4);
        assert_eq!(h, Poly::new(&SQUARE).unwrap());
        assert_eq!(
            Poly::hull(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
            Err(GeometryError::ZeroArea)
        );
        assert_eq!(
            Poly::hull(&[[0.0, 0.0]]),
            Err(GeometryError::TooFewVertices)
        );
        assert_eq!(Poly::hull(&[]), Err(GeometryError::TooFewVertices));
    }

    #[test]
    fn closest_point_outside_on_edge_and_vertex() {
        let sq = Poly::new(&SQUARE).unwrap();
        let r = closest_point_point_polygon(&v(0.5, -2.0), &sq);
        assert_eq!(r.location, PointLocation::Outside);
        assert!((r.point - v(0.5, 0.0)).norm() < 1e-15);
        assert!((r.normal - v(0.0, -1.0)).norm() < 1e-15);
        assert!((r.signed_distance - 2.0).abs() < 1e-15);
        // Vertex region.
        let r = closest_point_point_polygon(&v(2.0, 2.0), &sq);
        assert!((r.point - v(1.0, 1.0)).norm() < 1e-15);
        let s = 1.0 / libm::sqrt(2.0);
        assert!((r.normal - v(s, s)).norm() < 1e-15);
        assert!((r.signed_distance - libm::sqrt(2.0)).abs() < 1e-15);
    }

    #[test]
    fn closest_point_inside_points_out_through_nearest_edge() {
        let sq = Poly::new(&SQUARE).unwrap();
        let r = closest_point_point_polygon(&v(0.9, 0.4), &sq);
        assert_eq!(r.location, PointLocation::Inside);
        assert!((r.point - v(1.0, 0.4)).norm() < 1e-15);
        assert!((r.normal - v(1.0, 0.0)).norm() < 1e-15);
        assert!((r.signed_distance + 0.1).abs() < 1e-15);
        assert!(sq.contains(&v(0.9, 0.4)));
        assert!(!sq.contains(&v(1.1, 0.4)));
    }

    #[test]
    fn closest_point_on_boundary_uses_edge_or_vertex_normal() {
        let sq = Poly::new(&SQUARE).unwrap();
        let r = closest_point_point_polygon(&v(0.0, 0.3), &sq);
        assert_eq!(r.location, PointLocation::OnBoundary);
        assert_eq!(r.signed_distance, 0.0);
        assert!((r.normal - v(-1.0, 0.0)).norm() < 1e-15);
        let r = closest_point_point_polygon(&v(1.0, 0.0), &sq);
        assert_eq!(r.location, PointLocation::OnBoundary);
        let s = 1.0 / libm::sqrt(2.0);
        assert!((r.normal - v(s, -s)).norm() < 1e-15, "{:?}", r.normal);
        // Clockwise input gives the same answers.
        let mut rev = SQUARE;
        rev.reverse();
        let sq2 = Poly::new(&rev).unwrap();
        let r2 = closest_point_point_polygon(&v(0.0, 0.3), &sq2);
        assert!((r2.normal - v(-1.0, 0.0)).norm() < 1e-15);
    }

    #[test]
    fn non_finite_query_does_not_panic() {
        let sq = Poly::new(&SQUARE).unwrap();
        let r = closest_point_point_polygon(&v(f64::NAN, 0.0), &sq);
        assert!(!r.signed_distance.is_finite());
    }
}
