//! Safety for a robot with a body and feet (issue 11): the body disk and every
//! footprint stay out of the TRUE obstacles along the whole 1 kHz path, not
//! only at step ends. (Impossible scenarios, a start or goal without room for
//! the body, are refused: `host-sim/tests/bad_input.rs`.)
//!
//! The guarantee (see `Config::barrier_margin`): when every cycle is solved
//! (no relaxation), the step-end barrier rows with the arc margin and the foot
//! rows keep the CoM's continuous arc `body_radius + delta` clear of every
//! active obstacle's half-plane. The tests check it on the closed loop's 1 kHz
//! samples, against the true polygons.

use std::path::PathBuf;

use ldcbf_sim::scenario::{LoadOptions, load, scenario_dir};
use ldcbf_sim::sense::Perception;
use ldcbf_sim::sim::{SimOptions, run};
use ldcbf_sim::studies::batch::{BatchRequest, SeedRange, run_batch};
use ldcbf_sim::summarize;
use ldcbf_sim::world::robot::CONTACT_TOLERANCE;

/// Random layouts at delta = 0 (the tightest margin): no run's body or foot
/// overlaps an obstacle at any 1 kHz sample. At delta = 0 and a point CoM
/// the same layouts had the CoM dip up to 15 mm into obstacles between step
/// ends on 21 of 200 (the step ends alone were constrained).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "200 closed loops: run with --release (.ci/run does)"
)]
fn continuous_path_keeps_the_body_out_on_200_random_layouts() {
    let tmp = tempfile::tempdir().unwrap();
    let mut req = BatchRequest::new("random", SeedRange { start: 0, end: 200 });
    req.sets = vec![("delta".into(), "0.0".into())];
    req.out = Some(tmp.path().join("b"));
    let rep = run_batch(&req).unwrap();
    let a = &rep.aggregate;
    println!(
        "200 random, delta 0: success {}, body collisions {}, foot collisions {}, \
         min body clearance {:.4} m, min foot clearance {:.4} m, runs with a relaxed cycle {}",
        a.success,
        a.collisions,
        a.foot_collisions,
        a.min_body_clearance,
        a.min_footstep_clearance,
        a.runs_with_non_optimal
    );
    assert_eq!(a.runs, 200);
    assert_eq!(a.collisions, 0, "body collisions");
    assert_eq!(a.foot_collisions, 0, "foot collisions");
    assert!(a.min_body_clearance >= -CONTACT_TOLERANCE);
    assert!(a.min_footstep_clearance >= -CONTACT_TOLERANCE);
    // The robot walks: most layouts are crossed (a robot that stands still
    // would pass the checks above trivially).
    assert!(
        a.success >= 150,
        "only {} of 200 reached the goal",
        a.success
    );
}

/// Every shipped scenario, as shipped (known map or LiDAR, its own delta and
/// robot): no body or foot overlaps a true obstacle (with people who move: by
/// the robot's own motion).
#[test]
fn shipped_scenarios_keep_body_and_feet_out() {
    let mut names: Vec<PathBuf> = std::fs::read_dir(scenario_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 7);
    let mut failures = Vec::new();
    for path in &names {
        let sc = load(path.to_str().unwrap(), &LoadOptions::default()).unwrap();
        let r = run(
            &sc,
            SimOptions {
                record_scans: false,
                ..SimOptions::default()
            },
        )
        .unwrap();
        let s = summarize(&r);
        println!(
            "{:14} {:6} {:14} body {:+.3} m, foot {:+.3} m",
            sc.name,
            sc.perception.name(),
            s.outcome,
            s.min_body_clearance.unwrap_or(f64::INFINITY),
            s.min_footstep_clearance.unwrap_or(f64::INFINITY)
        );
        // With people who move, only the contacts where the robot moved into
        // an obstacle are the controller's (host-sim/src/sim/contacts.rs); on
        // a map at rest every contact is.
        let robot_failed = if s.moving_obstacles > 0 {
            s.contacts_robot > 0
        } else {
            s.collision || s.foot_collision
        };
        if robot_failed {
            failures.push(format!(
                "{} ({:?})",
                sc.name,
                sc.perception == Perception::Lidar
            ));
        }
    }
    assert!(failures.is_empty(), "body or foot collisions: {failures:?}");
}

/// The scenario families (`host-sim/src/world/families.rs`), 20 seeds each, at
/// `delta = 0.05`: the MPC alone and with RRT* subgoals on the known map (the
/// guarantee's domain), and the MPC alone with LiDAR perception: no body or
/// foot overlaps a true obstacle in any run. (With perception the guarantee
/// holds for the perceived pieces; that the true walls stay clear too rests
/// on the pieces holding the hits and on a straight wall staying one piece:
/// with the former split tolerance of 0.03 m, `corridor` seed 19 touched a
/// wall; the cases that still touch on other seeds are in docs/results.md.)
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "360 closed loops: run with --release (.ci/run does)"
)]
fn families_keep_body_and_feet_out() {
    use ldcbf_sim::plan::Planner;
    let tmp = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for family in [
        "corridor",
        "doorway",
        "cup",
        "wall-start",
        "clutter",
        "thin",
    ] {
        for (planner, perception) in [
            (Planner::None, Perception::Known),
            (Planner::RrtStar, Perception::Known),
            (Planner::None, Perception::Lidar),
        ] {
            let mut req = BatchRequest::new(family, SeedRange { start: 0, end: 20 });
            req.planner = Some(planner);
            req.perception = Some(perception);
            req.sets = vec![("delta".into(), "0.05".into())];
            req.out = Some(tmp.path().join(format!(
                "{family}-{}-{}",
                planner.name(),
                perception.name()
            )));
            let a = run_batch(&req).unwrap().aggregate;
            println!(
                "{family:10} {:8} {:5}: success {:2}/20, body collisions {}, foot collisions {}, \
                 min body {:+.3} m, min foot {:+.3} m",
                planner.name(),
                perception.name(),
                a.success,
                a.collisions,
                a.foot_collisions,
                a.min_body_clearance,
                a.min_footstep_clearance
            );
            if a.collisions + a.foot_collisions > 0 {
                failures.push(format!(
                    "{family} {} {}: {} body, {} foot",
                    planner.name(),
                    perception.name(),
                    a.collisions,
                    a.foot_collisions
                ));
            }
            // With the subgoals every family is crossed.
            if planner == Planner::RrtStar {
                assert!(a.success >= 18, "{family} with RRT*: {} of 20", a.success);
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}
