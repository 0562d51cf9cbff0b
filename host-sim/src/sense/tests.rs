//! Tests of the LiDAR, DBSCAN and the obstacle inference.

use super::*;

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

#[test]
fn simplification_contains_the_input() {
    let circle: Vec<_> = (0..100)
        .map(|i| {
            let a = core::f64::consts::TAU * f64::from(i) / 100.0;
            v(a.cos(), a.sin())
        })
        .collect();
    let s = simplify_outer(&infer::hull_of(&circle), 12);
    assert_eq!(s.len(), 12);
    let poly = Polygon::new(&s.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>()).unwrap();
    for p in &circle {
        assert!(poly.contains(p));
    }
}

/// Seeded uniform numbers in [0, 1) (xorshift64).
fn uniform(mut s: u64) -> impl FnMut() -> f64 {
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The quadratic form of [`simplify_outer`] (every edge rescanned per
/// removal, each collapse by `collapse_edge`), as it was before the heap: the
/// reference of the test below.
fn simplify_outer_by_scans(hull: &[Vector2<f64>], max: usize) -> Vec<Vector2<f64>> {
    let mut h = hull.to_vec();
    while h.len() > max.max(3) {
        let n = h.len();
        let mut best: Option<(usize, Vector2<f64>, f64)> = None;
        for i in 0..n {
            let Some((area, q)) =
                infer::collapse_edge(h[(i + n - 1) % n], h[i], h[(i + 1) % n], h[(i + 2) % n])
            else {
                continue;
            };
            if best.is_none_or(|(_, _, a)| area < a) {
                best = Some((i, q, area));
            }
        }
        let Some((i, q, _)) = best else {
            break;
        };
        let j = (i + 1) % n;
        h[i] = q;
        h.remove(j);
    }
    h
}

/// The heap's simplification is the scans' one, bit for bit (same vertices in
/// the same order), on hulls of random point sets, of rings of many points
/// (where equal areas tie) and of a LiDAR-like arc, for every vertex budget.
#[test]
fn simplification_by_heap_equals_the_scans() {
    let mut rnd = uniform(0x9e37_79b9_7f4a_7c15);
    let mut sets: Vec<Vec<Vector2<f64>>> = Vec::new();
    for k in 0..60 {
        let n = 5 + k * 3;
        sets.push(
            (0..n)
                .map(|_| v(4.0 * rnd() - 2.0, 3.0 * rnd() - 1.5))
                .collect(),
        );
    }
    for n in [7, 16, 100, 257, 600] {
        sets.push(
            (0..n)
                .map(|i| {
                    let a = core::f64::consts::TAU * i as f64 / n as f64;
                    v(0.6 * a.cos(), 0.6 * a.sin())
                })
                .collect(),
        );
        sets.push(
            (0..n)
                .map(|i| {
                    let a = 2.0 * i as f64 / n as f64;
                    let r = 1.0 + 0.01 * rnd();
                    v(3.0 + r * a.cos(), r * a.sin())
                })
                .collect(),
        );
    }
    for pts in &sets {
        let hull = infer::hull_of(pts);
        for max in [0, 3, 4, 5, 8, 12, 40] {
            let a = simplify_outer(&hull, max);
            let b = simplify_outer_by_scans(&hull, max);
            let bits = |h: &[Vector2<f64>]| {
                h.iter()
                    .map(|p| (p.x.to_bits(), p.y.to_bits()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(
                bits(&a),
                bits(&b),
                "{} hull vertices, max {max}",
                hull.len()
            );
        }
    }
}

/// `at_least_thick` decides as the width computed over every edge and
/// vertex did (`width >= t`), on random hulls, thin slivers and rings, for
/// thresholds around each hull's width (its exact value included).
#[test]
fn thickness_test_equals_the_width() {
    fn width(h: &[Vector2<f64>]) -> f64 {
        let n = h.len();
        (0..n)
            .map(|i| {
                let (a, b) = (h[i], h[(i + 1) % n]);
                let e = (b - a).normalize();
                h.iter()
                    .map(|p| (p - a).x * -e.y + (p - a).y * e.x)
                    .fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min)
    }
    let mut rnd = uniform(0x2545_f491_4f6c_dd1d);
    for k in 0..200 {
        let n = 3 + k % 50;
        let (sx, sy) = if k % 3 == 0 { (2.0, 0.02) } else { (1.0, 1.0) };
        let pts: Vec<_> = (0..n)
            .map(|i| {
                if k % 5 == 0 {
                    let a = core::f64::consts::TAU * i as f64 / n as f64;
                    v(sx * a.cos(), sy * a.sin())
                } else {
                    v(sx * rnd(), sy * rnd())
                }
            })
            .collect();
        let hull = infer::hull_of(&pts);
        if hull.len() < 3 {
            continue;
        }
        let w = width(&hull);
        for t in [
            0.0,
            -1.0,
            f64::NAN,
            w,
            w * 0.5,
            w * (1.0 - 1e-12),
            w * (1.0 + 1e-12),
            2.0 * w,
            0.05,
        ] {
            assert_eq!(
                infer::at_least_thick(&hull, t),
                w >= t,
                "width {w}, t {t}, {} vertices",
                hull.len()
            );
        }
    }
}

fn poly(pts: &[[f64; 2]]) -> Polygon {
    Polygon::new(pts).unwrap()
}

#[test]
fn perception_keeps_a_convex_box_whole_and_cuts_an_inside_corner() {
    let params = LidarParams::default();
    let o = v(0.0, 0.0);
    // A square seen corner-first (a diamond): two faces, one piece.
    let diamond = [poly(&[[1.5, 0.0], [2.0, -0.5], [2.5, 0.0], [2.0, 0.5]])];
    let rays = Lidar::new(params.clone(), 7)
        .unwrap()
        .scan_rays(o, 0.0, &diamond);
    let pts: Vec<_> = rays.iter().flatten().copied().collect();
    assert!(pts.len() > 20);
    let pieces = infer_obstacles(&rays, o, 0.0, &params);
    assert_eq!(pieces.len(), 1, "{pieces:?}");
    // Two walls meeting in an L around the sensor: one DBSCAN cluster,
    // whose hull covers the corner's free space; the pieces do not.
    let l = [
        poly(&[[-1.0, 0.5], [1.05, 0.5], [1.05, 0.55], [-1.0, 0.55]]),
        poly(&[[1.0, -1.0], [1.05, -1.0], [1.05, 0.55], [1.0, 0.55]]),
    ];
    let rays = Lidar::new(params.clone(), 7).unwrap().scan_rays(o, 0.3, &l);
    let pts: Vec<_> = rays.iter().flatten().copied().collect();
    let cl = clusters(&pts, params.eps, params.min_points);
    assert_eq!(cl.len(), 1);
    let free = v(0.7, 0.2); // on the ray toward (1, 0.29), 0.3 m short of the wall
    assert!(cluster_polygon(&cl[0], 0.05, 32).contains(&free));
    let pieces = infer_obstacles(&rays, o, 0.3, &params);
    assert!(pieces.len() >= 2, "{pieces:?}");
    for q in &pieces {
        assert!(!q.contains(&o) && !q.contains(&free), "{:?}", q.vertices());
    }
    // Deterministic and seeded: the same seed, the same pieces.
    let again = Lidar::new(params.clone(), 7).unwrap().scan_rays(o, 0.3, &l);
    assert_eq!(infer_obstacles(&again, o, 0.3, &params), pieces);
}

#[test]
fn lidar_params_validate_the_new_fields() {
    let ok = LidarParams::default();
    assert!(ok.validate().is_ok());
    let bad = |p: LidarParams| p.validate().unwrap_err().field;
    let b = LidarParams {
        breakpoint_angle: 2.0,
        ..ok.clone()
    };
    assert_eq!(bad(b), "breakpoint_angle");
    let b = LidarParams {
        line_tolerance: 0.0,
        ..ok.clone()
    };
    assert_eq!(bad(b), "line_tolerance");
    // Below 4 noise_sigma the noise alone splits straight walls.
    let b = LidarParams {
        noise_sigma: 0.02,
        ..ok.clone()
    };
    assert_eq!(bad(b), "line_tolerance");
    let b = LidarParams {
        noise_sigma: 0.02,
        line_tolerance: 0.08,
        ..ok.clone()
    };
    assert!(b.validate().is_ok());
    let b = LidarParams {
        free_margin: -1.0,
        ..ok
    };
    assert_eq!(bad(b), "free_margin");
}
