//! People who are hard to see (issue 35): 20 seeds of each of the families
//! `group-crossing`, `headon-offset` and `occluded-person`
//! (`host-sim/src/world/people_hard.rs`) with the LiDAR tracker
//! (`host-sim/src/sense/movers.rs`, `sense/track.rs`), planning on the
//! perceived map (`planner = "rrt_star"`) at `delta = 0.05`: the robot never
//! moves into a person (`contacts_robot`). Release builds only (`.ci/run`).

use ldcbf_sim::plan::Planner;
use ldcbf_sim::sense::Perception;
use ldcbf_sim::studies::batch::{Aggregate, BatchRequest, SeedRange, run_batch};

fn batch(family: &str, seeds: u64) -> Aggregate {
    let tmp = tempfile::tempdir().unwrap();
    let mut req = BatchRequest::new(
        family,
        SeedRange {
            start: 0,
            end: seeds,
        },
    );
    req.perception = Some(Perception::Lidar);
    req.planner = Some(Planner::RrtStar);
    req.sets = vec![("delta".into(), "0.05".into())];
    req.out = Some(tmp.path().join("b"));
    let a = run_batch(&req).unwrap().aggregate;
    println!(
        "{family}: {} runs, success {}, reached {}, contacts robot {} person {}, \
         min body clearance {:.3} m",
        a.runs, a.success, a.reached, a.contacts_robot, a.contacts_person, a.min_body_clearance
    );
    a
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "60 closed loops with LiDAR: run with --release (.ci/run does)"
)]
fn lidar_tracking_no_robot_caused_contact_on_people_hard_to_see() {
    let mut failed = Vec::new();
    for family in ["group-crossing", "headon-offset", "occluded-person"] {
        let a = batch(family, 20);
        assert_eq!(a.runs, 20);
        if a.contacts_robot != 0 {
            failed.push(format!(
                "{family}: {} robot-caused contacts",
                a.contacts_robot
            ));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}
