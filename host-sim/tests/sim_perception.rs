//! Perception for unknown maps (docs/maths.md §6): DBSCAN and the cluster
//! polygons on hand-made point sets, the simulated LiDAR against known
//! geometry, and the `crowded` scenario, where the controller sees only the
//! inferred obstacles and the CoM must stay out of the TRUE ones.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sense::Perception;
use ldcbf_sim::sense::{Lidar, LidarParams, cast_ray, cluster_polygon, clusters, dbscan};
use ldcbf_sim::sim::{Outcome, SimOptions, run};
use ldcbf_sim::summarize;
use ldcbf_sim::world::Polygon;

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

fn contains_all(poly: &Polygon, pts: &[Vector2<f64>]) {
    for p in pts {
        assert!(poly.contains(p), "{p:?} outside {:?}", poly.vertices());
    }
}

/// Smallest extent of a convex polygon across its edges (m).
fn width(poly: &Polygon) -> f64 {
    let h = poly.vertices();
    (0..h.len())
        .map(|i| {
            let (a, b) = (h[i], h[(i + 1) % h.len()]);
            let e = (b - a).normalize();
            h.iter()
                .map(|p| ((p - a).x * -e.y + (p - a).y * e.x).abs())
                .fold(0.0, f64::max)
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn dbscan_separates_groups_and_drops_noise() {
    // Two groups of 4 points 0.1 m apart, 2 m between them, one lone point.
    let mut pts: Vec<_> = (0..4).map(|i| v(0.1 * f64::from(i), 0.0)).collect();
    pts.extend((0..4).map(|i| v(2.0, 0.1 * f64::from(i))));
    pts.push(v(5.0, 5.0));
    let l = dbscan(&pts, 0.3, 3);
    assert!(l[..4].iter().all(|x| *x == Some(0)), "{l:?}");
    assert!(l[4..8].iter().all(|x| *x == Some(1)), "{l:?}");
    assert_eq!(l[8], None, "an isolated point is noise");
    // min_points = 1: every point is a core point, the lone one its own cluster.
    let l = dbscan(&pts, 0.3, 1);
    assert_eq!(l[8], Some(2));
    // A chain 0.25 m apart is one cluster at eps = 0.3 (density-connected),
    // and falls apart at eps = 0.2.
    let chain: Vec<_> = (0..10).map(|i| v(0.25 * f64::from(i), 1.0)).collect();
    assert_eq!(clusters(&chain, 0.3, 3).len(), 1);
    assert!(dbscan(&chain, 0.2, 3).iter().all(Option::is_none));
    // eps is inclusive; min_points counts the point itself.
    let pair = [v(0.0, 0.0), v(0.25, 0.0)];
    assert_eq!(dbscan(&pair, 0.25, 2), vec![Some(0), Some(0)]);
    assert_eq!(dbscan(&pair, 0.25, 3), vec![None, None]);
    // A border point (one core neighbour, too few of its own) joins the cluster.
    let mut b: Vec<_> = (0..3).map(|i| v(0.05 * f64::from(i), 0.0)).collect();
    b.push(v(0.38, 0.0)); // within 0.3 of (0.1, 0) only
    let l = dbscan(&b, 0.3, 3);
    assert_eq!(l, vec![Some(0); 4]);
}

#[test]
fn hull_of_a_cluster_is_its_convex_hull() {
    let pts = [
        v(0.0, 0.0),
        v(1.0, 0.0),
        v(1.0, 1.0),
        v(0.0, 1.0),
        v(0.5, 0.5),
        v(0.2, 0.7),
    ];
    let p = cluster_polygon(&pts, 0.05, 32);
    assert_eq!(p.len(), 4);
    contains_all(&p, &pts);
    let area: f64 = {
        let h = p.vertices();
        0.5 * (0..h.len())
            .map(|i| h[i].x * h[(i + 1) % h.len()].y - h[(i + 1) % h.len()].x * h[i].y)
            .sum::<f64>()
    };
    assert!((area - 1.0).abs() < 1e-12, "{area}");
}

#[test]
fn degenerate_clusters_become_valid_thin_obstacles() {
    let t = 0.05;
    // One point: a square of side t around it.
    let one = [v(1.0, 2.0)];
    let p = cluster_polygon(&one, t, 32);
    contains_all(&p, &one);
    assert!((width(&p) - t).abs() < 1e-9);
    // Two points: a rectangle along them, t thick, t/2 past each end.
    let two = [v(0.0, 0.0), v(0.3, 0.4)];
    let p = cluster_polygon(&two, t, 32);
    contains_all(&p, &two);
    assert_eq!(p.len(), 4);
    assert!((width(&p) - t).abs() < 1e-9);
    // Collinear points (a wall seen edge-on, no noise): thin rectangle.
    let line: Vec<_> = (0..7)
        .map(|i| v(0.1 * f64::from(i), 0.05 * f64::from(i)))
        .collect();
    let p = cluster_polygon(&line, t, 32);
    contains_all(&p, &line);
    assert!((width(&p) - t).abs() < 1e-9);
    // A hull thinner than t (noisy wall): thickened the same way.
    let sliver = [v(0.0, 0.0), v(1.0, 0.0), v(0.5, 0.01), v(0.2, -0.005)];
    let p = cluster_polygon(&sliver, t, 32);
    contains_all(&p, &sliver);
    assert!(width(&p) >= t - 1e-9);
}

#[test]
fn hulls_with_many_vertices_are_simplified_outwards() {
    let ring: Vec<_> = (0..200)
        .map(|i| {
            let a = core::f64::consts::TAU * f64::from(i) / 200.0;
            v(3.0 + 0.8 * a.cos(), -1.0 + 0.8 * a.sin())
        })
        .collect();
    for max in [32, 12, 6] {
        let p = cluster_polygon(&ring, 0.05, max);
        assert!(p.len() <= max, "{} > {max}", p.len());
        contains_all(&p, &ring);
    }
    // Capacity 32 is the default.
    assert_eq!(LidarParams::default().max_vertices, 32);
}

fn square(c: [f64; 2], h: f64) -> Polygon {
    Polygon::new(&[
        [c[0] - h, c[1] - h],
        [c[0] + h, c[1] - h],
        [c[0] + h, c[1] + h],
        [c[0] - h, c[1] + h],
    ])
    .unwrap()
}

#[test]
fn lidar_hits_the_true_polygons_within_range() {
    let obs = [square([2.0, 0.0], 0.5)];
    let o = v(0.0, 0.0);
    assert!((cast_ray(o, v(1.0, 0.0), &obs, 3.0).unwrap() - 1.5).abs() < 1e-12);
    assert_eq!(cast_ray(o, v(-1.0, 0.0), &obs, 3.0), None);
    assert_eq!(cast_ray(o, v(1.0, 0.0), &obs, 1.4), None, "beyond range");
    // Noise-free scan: every hit lies on the square's boundary, facing rays only.
    let params = LidarParams {
        noise_sigma: 0.0,
        ..LidarParams::default()
    };
    let mut lidar = Lidar::new(params.clone(), 0).unwrap();
    let pts = lidar.scan(o, 0.0, &obs);
    // The square spans atan(0.5/1.5) each side of the x axis: 37 one-degree rays.
    assert_eq!(pts.len(), 37);
    for p in &pts {
        let d = ldcbf_controller::closest_point_point_polygon(p, &obs[0]).signed_distance;
        assert!(d.abs() < 1e-9);
    }
    // One cluster, one inferred obstacle containing every hit.
    let (_, polys) = Lidar::new(params, 0).unwrap().perceive(o, 0.0, &obs);
    assert_eq!(polys.len(), 1);
    contains_all(&polys[0], &pts);
}

/// Runs a regression scenario with `delta = 0.05`: no body penetration of the
/// TRUE map over the 1 kHz CoM trajectory, and in no cycle does a perceived
/// piece contain the robot (nor enter the free space its scan saw).
fn body_stays_clear(name: &str) {
    let sc = load(
        name,
        &LoadOptions {
            seed: None,
            sets: vec![("delta".into(), "0.05".into())],
        },
    )
    .unwrap();
    assert_eq!(sc.perception, Perception::Lidar);
    let r = run(&sc, SimOptions::default()).unwrap();
    let s = summarize(&r);
    let c = s.min_com_clearance.unwrap();
    let body = sc.robot.body_radius;
    assert!(body >= 0.25, "default humanoid body");
    assert!(
        c - body >= 0.0,
        "{name}: body penetrates a true obstacle by {} m",
        body - c
    );
    assert!(!r.scans.is_empty());
    for scan in &r.scans {
        for (k, poly) in scan.obstacles.iter().enumerate() {
            let d =
                ldcbf_controller::closest_point_point_polygon(&scan.origin, poly).signed_distance;
            assert!(
                d > 0.0,
                "{name}: cycle {} piece {k} contains the robot",
                scan.cycle
            );
        }
    }
}

/// Issue 11: the robot starts inside a U-shaped cup (one DBSCAN cluster whose
/// hull covered it); its body must never touch the true walls.
#[test]
fn cup_mouth_perception_keeps_the_body_clear() {
    body_stays_clear("cup-mouth");
}

/// Issue 11: two walls meeting at a corner near the start.
#[test]
fn corner_start_perception_keeps_the_body_clear() {
    body_stays_clear("corner-start");
}

#[test]
fn lidar_noise_is_zero_mean_with_the_given_sigma_and_seeded() {
    // A long wall x = 1, seen across; the error along x is the noise on x.
    let wall = Polygon::new(&[[1.0, -50.0], [1.2, -50.0], [1.2, 50.0], [1.0, 50.0]]).unwrap();
    let params = LidarParams {
        rays: 20_000,
        range: 3.0,
        ..LidarParams::default()
    };
    let mut a = Lidar::new(params.clone(), 42).unwrap();
    let pts = a.scan(v(0.0, 0.0), 0.0, std::slice::from_ref(&wall));
    let e: Vec<f64> = pts.iter().map(|p| p.x - 1.0).collect();
    let n = e.len() as f64;
    let mean = e.iter().sum::<f64>() / n;
    let sd = (e.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    assert!(n > 1000.0);
    assert!(mean.abs() < 0.001, "mean {mean}");
    assert!((sd - 0.01).abs() < 0.001, "sigma {sd}");
    let again = Lidar::new(params, 42)
        .unwrap()
        .scan(v(0.0, 0.0), 0.0, std::slice::from_ref(&wall));
    assert_eq!(pts, again, "same seed, same noise");
}

/// Report figure 12: the crowded map, unknown to the controller.
#[test]
fn crowded_reaches_the_goal_with_lidar_and_no_true_collision() {
    let sc = load("crowded", &LoadOptions::default()).unwrap();
    assert_eq!(sc.perception, Perception::Lidar);
    assert!(sc.obstacles.len() >= 18, "about 20 obstacles");
    let r = run(&sc, SimOptions::default()).unwrap();
    let s = summarize(&r);
    assert_eq!(r.outcome, Outcome::GoalReached, "{s:#?}");
    assert!(s.success);
    let c = s.min_com_clearance.unwrap();
    assert!(
        c >= 0.0 && !s.collision,
        "min CoM clearance to the true map {c}"
    );
    // The controller saw inferred obstacles only: one scan per cycle, and the
    // obstacle count it was given is that scan's.
    assert_eq!(r.scans.len(), r.cycles.len());
    for (scan, c) in r.scans.iter().zip(&r.cycles) {
        assert_eq!(scan.cycle, c.index);
        assert_eq!(c.obstacles_seen, scan.obstacles.len());
        for hp in &c.half_planes {
            assert!(hp.obstacle < scan.obstacles.len());
        }
    }
    // Pieces come from the occupancy map (cells remembered beyond the
    // LiDAR's range included): rectangles of whole cells, never containing
    // the robot.
    for scan in &r.scans {
        for poly in &scan.obstacles {
            let d =
                ldcbf_controller::closest_point_point_polygon(&scan.origin, poly).signed_distance;
            assert!(d > 0.0, "piece at {d} m from the sensor");
            assert_eq!(poly.vertices().len(), 4);
        }
    }
}
