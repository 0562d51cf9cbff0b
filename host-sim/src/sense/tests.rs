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
