//! Unknown maps (`perception = "lidar"` with `planner = "rrt_star"`): the
//! occupancy map remembers, the path is planned on the map seen so far and
//! replanned, and the robot meets each occlusion class of `scenarios/`
//! (a small obstacle behind a larger one, a needle along the path, a wall
//! across a cup's arm, a cup seen from its mouth) without touching the TRUE
//! map. The release-only test runs 20 seeds of every layout family.

use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sense::{CellState, Perception};
use ldcbf_sim::sim::{Outcome, ReplanReason, SimOptions, SimResult, run};
use ldcbf_sim::summarize;

/// Runs a shipped unknown-map scenario; checks it is one, that the goal is
/// reached and that neither the body nor a foot touched a true obstacle.
fn reaches_without_contact(name: &str) -> SimResult {
    let sc = load(name, &LoadOptions::default()).unwrap();
    assert_eq!(sc.perception, Perception::Lidar, "{name}");
    assert_eq!(sc.planner.name(), "rrt_star", "{name}");
    let r = run(&sc, SimOptions::default()).unwrap();
    let s = summarize(&r);
    assert_eq!(r.outcome, Outcome::GoalReached, "{name}: {s:#?}");
    assert!(!s.collision && !s.foot_collision, "{name}: {s:#?}");
    let m = s.mapping.as_ref().expect("a LiDAR run has a map");
    assert!(m.plans >= 1 && m.plan_failures == 0, "{name}: {m:?}");
    assert_eq!(m.map_updates, r.cycles.len());
    r
}

/// The map at the end holds what the robot walked past: the cells of the
/// true obstacles' near faces are occupied, the cells it walked through are
/// free, and no piece handed to the controller contains the robot.
fn map_is_consistent(r: &SimResult) {
    let log = r.mapping.as_ref().unwrap();
    let m = &log.map;
    for s in r.samples.iter().step_by(100) {
        assert_eq!(m.state_at(s.position), CellState::Free, "walked through");
    }
    let occupied = m
        .states()
        .iter()
        .filter(|s| **s == CellState::Occupied)
        .count();
    assert!(occupied > 20, "{occupied} occupied cells");
    for scan in &r.scans {
        for p in &scan.obstacles {
            assert!(!p.contains(&scan.origin), "cycle {}", scan.cycle);
        }
    }
}

#[test]
fn a_small_obstacle_hidden_behind_a_large_one_is_met_safely() {
    let r = reaches_without_contact("occluded");
    map_is_consistent(&r);
    // The hidden box was seen: occupied cells on its boundary by the end.
    let m = &r.mapping.as_ref().unwrap().map;
    let small = &r.scenario.obstacles[1];
    let seen = (0..m.height)
        .flat_map(|j| (0..m.width).map(move |i| (i, j)))
        .filter(|&(i, j)| m.state(i, j) == CellState::Occupied)
        .any(|(i, j)| {
            ldcbf_controller::closest_point_point_polygon(&m.centre(i, j), small)
                .signed_distance
                .abs()
                < 0.04
        });
    assert!(seen, "the hidden box is in the map");
}

/// The capture-step speed limit (`ldcbf_sim::sim::capture`,
/// `lidar.map.capture_speed_limit`): each cycle's cap is in `[0, vx_max]`,
/// the controller's optimal plans keep their longitudinal velocity under it,
/// and it binds as the robot walks towards the box's shadow; off (the
/// default), no cycle has a cap.
#[test]
fn the_capture_speed_limit_binds_and_the_plans_keep_it() {
    let with = |on: &str| {
        let sets = vec![("lidar.map.capture_speed_limit".to_string(), on.to_string())];
        load("occluded", &LoadOptions { seed: None, sets }).unwrap()
    };
    let r = run(&with("true"), SimOptions::default()).unwrap();
    let s = summarize(&r);
    assert_eq!(r.outcome, Outcome::GoalReached, "{s:#?}");
    assert!(!s.collision && !s.foot_collision, "{s:#?}");
    let vx_max = r.scenario.config.vx_max;
    assert_eq!(r.scans.len(), r.cycles.len());
    let mut bound = 0;
    for (scan, c) in r.scans.iter().zip(&r.cycles) {
        assert_eq!(scan.cycle, c.index);
        let cap = scan.speed_cap;
        assert!((0.0..=vx_max).contains(&cap), "cycle {}: {cap}", c.index);
        bound += usize::from(cap < vx_max);
        if c.output.info.source == ldcbf_controller::CommandSource::Optimal {
            for s in &c.output.plan.states {
                let lon = s.velocity.x * s.heading.cos() + s.velocity.y * s.heading.sin();
                assert!(lon <= cap + 1e-9, "cycle {}: {lon} > {cap}", c.index);
            }
        }
    }
    assert!(bound > 0, "the cap never binds");
    let off = run(&with("false"), SimOptions::default()).unwrap();
    assert!(off.scans.iter().all(|s| s.speed_cap == f64::INFINITY));
    let default = reaches_without_contact("occluded");
    assert!(default.scans.iter().all(|s| s.speed_cap == f64::INFINITY));
}

#[test]
fn a_needle_along_the_path_is_seen_and_avoided() {
    let r = reaches_without_contact("needle");
    map_is_consistent(&r);
}

#[test]
fn a_wall_across_a_cup_arm_is_passed() {
    let r = reaches_without_contact("cup-arm");
    map_is_consistent(&r);
}

/// The first plan goes through the unknown space behind the cup's mouth;
/// when the back wall is seen the path is blocked and replanned around.
#[test]
fn a_cup_seen_from_its_mouth_is_replanned_around() {
    let r = reaches_without_contact("cup-front");
    map_is_consistent(&r);
    let plans = &r.mapping.as_ref().unwrap().plans;
    assert_eq!(plans[0].reason, ReplanReason::Initial);
    assert!(
        plans[0].subgoals.iter().all(|p| p.y.abs() < 0.5),
        "the first plan goes straight through the unknown: {:?}",
        plans[0].subgoals
    );
    assert!(
        plans.iter().any(|p| p.reason == ReplanReason::Blocked),
        "{:?}",
        plans.iter().map(|p| p.reason).collect::<Vec<_>>()
    );
    assert!(
        plans
            .last()
            .unwrap()
            .subgoals
            .iter()
            .any(|p| p.y.abs() > 0.8),
        "the last plan goes around an arm"
    );
}

/// The robot starting inside a cup (issue 11's layout) walks out by its
/// mouth and around with the map and the planner.
#[test]
fn the_cup_mouth_start_reaches_the_goal_with_planning() {
    let sc = load(
        "cup-mouth",
        &LoadOptions::with_sets(&[("planner", "\"rrt_star\""), ("delta", "0.05")]),
    )
    .unwrap();
    let r = run(&sc, SimOptions::default()).unwrap();
    let s = summarize(&r);
    assert_eq!(r.outcome, Outcome::GoalReached, "{s:#?}");
    assert!(!s.collision && !s.foot_collision);
}

/// A family layout with LiDAR (`rays` per scan), the map and planning.
fn study_run(family: &str, seed: u64, delta: &str, rays: &str) -> ldcbf_sim::report::Summary {
    let sc = load(
        family,
        &LoadOptions {
            seed: Some(seed),
            sets: vec![
                ("perception".into(), "\"lidar\"".into()),
                ("planner".into(), "\"rrt_star\"".into()),
                ("delta".into(), delta.into()),
                ("lidar.rays".into(), rays.into()),
            ],
        },
    )
    .unwrap();
    let options = SimOptions {
        record_scans: false,
        ..SimOptions::default()
    };
    summarize(&run(&sc, options).unwrap())
}

/// Needle class: `crowded` seed 174, a 0.73 m sliver of 2.08 degrees whose
/// tip points at the robot on its way, met at both deltas with the SPEC's 1
/// degree between rays (360) and with 0.25 degree (1440). With 1 degree the
/// needle is hit by one to three rays a scan, close to its tip, but its
/// cells had been cleared by the rays beside it and one hit a scan left them
/// free: the body touched it (-27 mm at delta = 0.05). A hit now makes its
/// cell occupied whatever misses came before (`lidar.map.hit_overrides_misses`,
/// docs/safety.md, "A hit is an obstacle now").
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p ldcbf-sim --test sim_unknown_maps"
)]
fn the_crowded_174_needle_is_seen_in_time() {
    for rays in ["360", "1440"] {
        for delta in ["0.05", "0.0"] {
            let s = study_run("crowded", 174, delta, rays);
            assert!(
                s.success && !s.collision && !s.foot_collision,
                "{rays} rays, delta {delta}: {s:#?}"
            );
        }
    }
}

/// Noise-band class: `corridor` seeds 101, 109, 141 and 157 draw 0.7 m
/// corridors (the narrowest the family draws, 5.9 cm of slack a side at
/// delta = 0). With the single-hit rule a wall is seen up to two cells in
/// front of its face (noise hits in the 3.5 cm its rays never clear), the
/// cycles turn infeasible and the body touches a side wall; with the faces
/// fitted (`ldcbf_sim::sense::faces`, docs/safety.md) each run reaches the
/// goal without contact.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p ldcbf-sim --test sim_unknown_maps"
)]
fn narrow_corridors_at_delta_0_keep_off_the_walls() {
    for seed in [101, 109, 141, 157] {
        let s = study_run("corridor", seed, "0.0", "360");
        assert!(
            s.success && !s.collision && !s.foot_collision,
            "seed {seed}: {s:#?}"
        );
    }
}

/// Bump class: corridors of the second unseen set (`corridor` seeds 209,
/// 224 and 248 at delta = 0.05; 218, 232, 248 and 282 at delta = 0). A
/// noise hit in the free row in front of a wall's face makes a one-cell
/// piece there (a bump); with the paper's closest-point normal its
/// half-plane, taken at the cell's corner nearest the robot, crossed the
/// corridor ahead, every cycle near it was infeasible, the safety rows gave
/// way by up to 0.29 m and the body touched a wall in each (209: -128 mm).
/// With the half-planes at vertices turned along the way
/// (`Config::turn_vertex_normals`, on with LiDAR and a planner;
/// docs/safety.md) none touches.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p ldcbf-sim --test sim_unknown_maps"
)]
fn corridor_bumps_do_not_turn_into_half_planes_across_the_way() {
    for (delta, seeds) in [
        ("0.05", &[209, 224, 248][..]),
        ("0.0", &[218, 232, 248, 282]),
    ] {
        for &seed in seeds {
            let s = study_run("corridor", seed, delta, "360");
            assert!(
                !s.collision && !s.foot_collision,
                "seed {seed}, delta {delta}: {s:#?}"
            );
        }
    }
}

/// The same class with 0.25 degree between rays (1440 rays, four times the
/// noise hits per wall cell): `corridor` seed 119 at delta = 0.05.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p ldcbf-sim --test sim_unknown_maps"
)]
fn corridor_119_with_1440_rays_keeps_off_the_walls() {
    let s = study_run("corridor", 119, "0.05", "1440");
    assert!(s.success && !s.collision && !s.foot_collision, "{s:#?}");
}

/// 20 seeds of every layout family with LiDAR (the default 360 rays), the
/// map and planning at delta = 0.05: no body or foot contact with the true
/// map in any run.
/// Release builds only (CI's release section runs it, on every core).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "release only: cargo test --release -p ldcbf-sim --test sim_unknown_maps"
)]
fn families_with_lidar_and_planning_keep_body_and_feet_out() {
    let families = [
        "corridor",
        "doorway",
        "cup",
        "wall-start",
        "clutter",
        "thin",
        "random",
        "crowded",
    ];
    let cases: Vec<(&str, u64)> = families
        .iter()
        .flat_map(|f| (100..120).map(move |s| (*f, s)))
        .collect();
    let next = std::sync::atomic::AtomicUsize::new(0);
    let jobs = std::thread::available_parallelism().map_or(2, |n| n.get());
    let results: Vec<Row> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..jobs)
            .map(|_| {
                scope.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(&(f, seed)) = cases.get(k) else {
                            return out;
                        };
                        let s = study_run(f, seed, "0.05", "360");
                        let m = s.mapping.clone().expect("a LiDAR run has a map");
                        out.push(Row {
                            family: f,
                            seed,
                            success: s.success,
                            contact: s.collision || s.foot_collision,
                            stuck: s.ended == "stuck",
                            body: s.min_body_clearance.unwrap_or(f64::INFINITY),
                            foot: s.min_footstep_clearance.unwrap_or(f64::INFINITY),
                            map: m,
                        });
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap())
            .collect()
    });
    assert_eq!(results.len(), cases.len());
    print_table(&families, &results);
    let contacts: Vec<String> = results
        .iter()
        .filter(|r| r.contact)
        .map(|r| {
            format!(
                "{} seed {}: body {:+.3} m, foot {:+.3} m",
                r.family, r.seed, r.body, r.foot
            )
        })
        .collect();
    assert!(contacts.is_empty(), "contacts: {contacts:?}");
}

/// One run of the release test.
struct Row {
    family: &'static str,
    seed: u64,
    success: bool,
    contact: bool,
    stuck: bool,
    body: f64,
    foot: f64,
    map: ldcbf_sim::report::MappingSummary,
}

/// The per-family table of the release test (printed with `--nocapture`).
fn print_table(families: &[&str], rows: &[Row]) {
    println!(
        "| family | success | contacts | stuck | min body / foot [mm] | replans mean / max | map update p50 / max [ms] | plan p50 / max [ms] |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for f in families {
        let r: Vec<&Row> = rows.iter().filter(|r| r.family == *f).collect();
        let n = r.len();
        let min = |g: fn(&Row) -> f64| r.iter().map(|x| g(x)).fold(f64::INFINITY, f64::min);
        let max = |g: fn(&Row) -> f64| r.iter().map(|x| g(x)).fold(0.0, f64::max);
        let med = |g: fn(&Row) -> f64| {
            let mut v: Vec<f64> = r.iter().map(|x| g(x)).collect();
            v.sort_by(f64::total_cmp);
            v.get(n / 2).copied().unwrap_or(0.0)
        };
        println!(
            "| {f} | {}/{n} | {} | {} | {:+.0} / {:+.0} | {:.1} / {:.0} | {:.2} / {:.1} | {:.0} / {:.0} |",
            r.iter().filter(|x| x.success).count(),
            r.iter().filter(|x| x.contact).count(),
            r.iter().filter(|x| x.stuck).count(),
            1e3 * min(|x| x.body),
            1e3 * min(|x| x.foot),
            r.iter().map(|x| x.map.replans as f64).sum::<f64>() / n.max(1) as f64,
            max(|x| x.map.replans as f64),
            med(|x| x.map.map_update_p50_ms),
            max(|x| x.map.map_update_max_ms),
            med(|x| x.map.plan_time_p50_ms),
            max(|x| x.map.plan_time_max_ms),
        );
    }
}
