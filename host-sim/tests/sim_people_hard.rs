//! The people families of issue 35 on 20 seeds each: the robot never moves
//! into a person (`contacts_robot`) with the LiDAR tracker
//! (`host-sim/src/sense/movers.rs`, `sense/track.rs`), planning on the
//! perceived map (`planner = "rrt_star"`) at `delta = 0.05`; and the named
//! regressions of contacts found on unseen seeds. Release builds only
//! (`.ci/run`).

mod people_batch;

use people_batch::{assert_no_robot_caused_contact, lidar_batch, with_reacting};

/// The scripted families issue 35 added (`world/people_hard.rs`, and
/// `room-crossing` of `world/people.rs`); with the families of people who
/// react (`world/crowd/families.rs`), every new people family. The older `crossing` and
/// `headon` are `sim_people`'s; `crowd` (constant-velocity people crossing
/// the robot's start) still has robot-caused contacts (seeds 0 and 249,
/// docs/results.md) and is not asserted here.
const NEW_SCRIPTED: &[&str] = &[
    "room-crossing",
    "group-crossing",
    "headon-offset",
    "occluded-person",
];

/// Seeds 0..20 of every new people family (280 closed loops).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "280 closed loops with LiDAR: run with --release (.ci/run does)"
)]
fn every_new_people_family_on_20_seeds_has_no_robot_caused_contact() {
    let families = with_reacting(NEW_SCRIPTED);
    assert_eq!(families.len(), 14);
    let mut failed = Vec::new();
    for family in &families {
        let a = lidar_batch(family, 0, 20);
        assert_eq!(a.runs, 20, "{family}");
        if a.contacts_robot != 0 {
            failed.push(format!(
                "{family}: {} robot-caused contacts",
                a.contacts_robot
            ));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}

/// Regression (`crowd` seed 601, unseen seeds 600..619): with walls taken
/// out of the people detector from 0.5 m of straight face, people of the
/// crowd standing side by side with their octagon faces lined up were left
/// to the map as a wall, and the robot walked into one (the same run
/// without the walls step, or from 0.8 m, has no contact;
/// `TrackParams::wall_length`).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "a closed loop with LiDAR: run with --release (.ci/run does)"
)]
fn crowd_seed_601_people_side_by_side_are_no_wall() {
    assert_no_robot_caused_contact(&[("crowd", 601)]);
}

/// Regression (`crowd` seeds 614, on main since 4f008a8, and 715, unseen
/// seeds 700..719): a person walking at the robot at 0.2-0.3 m/s was never
/// given a velocity (two standard deviations of the filter's steady-state
/// estimate are about 0.31 m/s), stood in the map as a wall for seconds, and
/// the robot walked into them. Travelling 0.3 m is evidence of motion too
/// (`TrackParams::still_radius`).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "closed loops with LiDAR: run with --release (.ci/run does)"
)]
fn crowd_people_walking_slowly_at_the_robot_are_seen_moving() {
    assert_no_robot_caused_contact(&[("crowd", 614), ("crowd", 715)]);
}

/// Regressions of the reachable set's variants that were not kept
/// (docs/results.md, "People hard to track"): `circle-crossing` seed 517
/// walked into a person with the set grown for 0.4 s, and `orca-crowd` seed
/// 416 walked into a slow walker ahead with a constant margin `r(grow)`. With
/// the default (the set grown over the whole horizon) neither run has a
/// robot-caused contact.
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "two closed loops with LiDAR: run with --release (.ci/run does)"
)]
fn the_reachable_set_variants_that_failed_keep_their_cases_clear() {
    assert_no_robot_caused_contact(&[("circle-crossing", 517), ("orca-crowd", 416)]);
}
