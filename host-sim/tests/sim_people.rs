//! People who move (issue 20): on the `crossing` and `headon` families, with
//! the obstacles' velocities given to the controller, the robot never moves
//! into a person (`contacts_robot`, `ldcbf_sim::sim::ContactCause::Robot`).
//! Contacts where a person walks into the standing robot are counted apart
//! and are not failures. Release builds only (`.ci/run`).

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
