//! People who move (issue 20): on the `crossing` and `headon` families, with
//! the obstacles' velocities given to the controller, the robot never moves
//! into a person (`contacts_robot`, `ldcbf_sim::sim::ContactCause::Robot`).
//! Contacts where a person walks into the standing robot are counted apart
//! and are not failures. The same with LiDAR: the people are tracked
//! (`host-sim/src/sense/movers.rs`), kept out of the occupancy map and given
//! to the controller with their estimated velocities. Release builds only
//! (`.ci/run`).

use ldcbf_sim::sense::Perception;
use ldcbf_sim::studies::batch::{Aggregate, BatchRequest, SeedRange, run_batch};

fn batch(family: &str, perception: Perception, seeds: u64) -> Aggregate {
    let tmp = tempfile::tempdir().unwrap();
    let mut req = BatchRequest::new(
        family,
        SeedRange {
            start: 0,
            end: seeds,
        },
    );
    req.perception = Some(perception);
    req.out = Some(tmp.path().join("b"));
    let a = run_batch(&req).unwrap().aggregate;
    println!(
        "{family} / {}: {} runs, success {}, reached {}, contacts robot {} person {}, \
         min body clearance {:.3} m",
        perception.name(),
        a.runs,
        a.success,
        a.reached,
        a.contacts_robot,
        a.contacts_person,
        a.min_body_clearance
    );
    a
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "40 closed loops: run with --release (.ci/run does)"
)]
fn known_velocities_no_robot_caused_contact_on_crossing_and_headon() {
    for family in ["crossing", "headon"] {
        let a = batch(family, Perception::Known, 20);
        assert_eq!(a.runs, 20);
        assert_eq!(
            a.contacts_robot, 0,
            "{family}: the robot moved into a person"
        );
        // The robot walks through: a robot that stood still would pass the
        // check above trivially.
        assert!(
            a.reached >= 18,
            "{family}: only {} of 20 reached",
            a.reached
        );
    }
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "40 closed loops with LiDAR: run with --release (.ci/run does)"
)]
fn lidar_tracking_no_robot_caused_contact_on_crossing_and_headon() {
    // The velocities come from the LiDAR tracker (`lidar.track_moving` in
    // scenarios/<family>.toml), the people are kept out of the occupancy map.
    for family in ["crossing", "headon"] {
        let a = batch(family, Perception::Lidar, 20);
        assert_eq!(a.runs, 20);
        assert_eq!(
            a.contacts_robot, 0,
            "{family}: the robot moved into a person it tracked"
        );
        assert!(
            a.reached >= 18,
            "{family}: only {} of 20 reached",
            a.reached
        );
    }
}
