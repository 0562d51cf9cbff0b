//! People who react (issue 35): a hand-written `[[people]]` scenario walked
//! with the true velocities, and a few cases of the crowd-navigation
//! benchmark (`ldcbf-sim crowdnav`) with our controller and with the ORCA
//! robot. Release builds only (`.ci/run`).

use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sense::Perception;
use ldcbf_sim::sim::{ContactCause, Outcome, SimOptions, run};
use ldcbf_sim::studies::crowdnav::{
    CrowdNavRequest, RobotPolicy, run_crowdnav, summarize, time_limit,
};
use ldcbf_sim::world::crowd::families::CrowdNavLayout;

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "a closed loop: run with --release (.ci/run does)"
)]
fn the_hand_written_people_walk_and_the_robot_walks_into_none() {
    let sc = load("people-walk", &LoadOptions::default()).unwrap();
    assert_eq!(sc.people.len(), 4);
    let r = run(&sc, SimOptions::default()).unwrap();
    assert_eq!(r.outcome, Outcome::GoalReached);
    let robot: Vec<_> = r
        .contacts
        .iter()
        .filter(|c| c.cause == ContactCause::Robot)
        .collect();
    assert!(robot.is_empty(), "{robot:?}");
    // The people moved: the clearance at the start (people 4 m away and
    // more) is not the clearance a few seconds later, when the ORCA crosser
    // stands on the robot's line.
    let at = |t: f64| r.samples[(t / 1e-3) as usize].clearance;
    assert!(
        at(0.0) > 3.0 && at(3.0) < at(0.0) - 0.5,
        "{} {}",
        at(0.0),
        at(3.0)
    );
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "closed loops: run with --release (.ci/run does)"
)]
fn a_few_crowdnav_cases_run_for_both_robots() {
    for robot in [RobotPolicy::Controller, RobotPolicy::Orca] {
        for visible in [false, true] {
            let req = CrowdNavRequest {
                layout: CrowdNavLayout::Circle,
                humans: 5,
                cases: 0..4,
                robot_visible: visible,
                perception: Perception::Known,
                robot,
                jobs: 2,
            };
            let rows = run_crowdnav(&req).unwrap();
            let seeds: Vec<u64> = rows.iter().map(|r| r.seed).collect();
            assert_eq!(seeds, vec![0, 1, 2, 3], "in seed order");
            for r in &rows {
                let kinds = [r.success, r.collision, r.timeout];
                assert_eq!(kinds.iter().filter(|&&k| k).count(), 1, "{r:?}");
                assert!(r.min_separation.is_finite(), "{r:?}");
                assert!(r.time <= time_limit() + 1e-6, "{r:?}");
            }
            let s = summarize(&rows);
            println!("{robot:?} visible {visible}: {s:?}");
            // Measured: with known velocities and a visible robot, no
            // robot-caused contact in 100 cases (docs/results.md); with an
            // invisible robot 6 of 100 cases have one, so none is asserted.
            if robot == RobotPolicy::Controller && visible {
                assert_eq!(s.robot_collision, 0.0, "{rows:?}");
            }
            // The humans cross the robot's way: it comes within the
            // discomfort distance of someone in some case.
            assert!(s.discomfort > 0.0 || s.collision > 0.0, "{s:?}");
        }
    }
}
