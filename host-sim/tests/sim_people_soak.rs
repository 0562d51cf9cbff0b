//! The soak test of the people families (issue 35): every CI run draws new
//! seeds, two of every family with people (the scripted ones of
//! `world/people.rs` and `world/people_hard.rs`, and every family of people
//! who react, `world/crowd/families.rs`), with the LiDAR tracker, planning on
//! the perceived map at `delta = 0.05`, and asserts that the robot never
//! moves into a person (`contacts_robot`). A failure prints the family and
//! the seeds with the command that replays one; keep it as a named
//! regression test and fix the cause (never pin the seed to pass).
//! `LDCBF_SOAK_SEED=S` replays the draw that starts at seed `S`. Release
//! builds only. Not in `.ci/run` yet: `crowd` seeds 0 and 249 still have a
//! robot-caused contact (docs/results.md, "People hard to track"), so a
//! draw that includes `crowd` fails now and then; it joins CI once those
//! are fixed (the 14 new families are asserted on seeds 0..19 in CI by
//! `sim_people_hard`).

mod people_batch;

use std::time::{SystemTime, UNIX_EPOCH};

use people_batch::{lidar_batch, with_reacting};

/// The scripted families with people (constant velocities).
const SCRIPTED: &[&str] = &[
    "crossing",
    "headon",
    "crowd",
    "room-crossing",
    "group-crossing",
    "headon-offset",
    "occluded-person",
];

/// Seeds per family and run.
const PER_FAMILY: u64 = 2;

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "34 closed loops with LiDAR on new seeds: run with --release (.ci/run does)"
)]
fn people_families_on_new_seeds_never_see_the_robot_walk_into_a_person() {
    let base = match std::env::var("LDCBF_SOAK_SEED") {
        Ok(s) => s.parse::<u64>().expect("LDCBF_SOAK_SEED: a seed"),
        // Above the seeds of the docs' studies (0..500); a new draw per run.
        Err(_) => {
            let ns = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            1_000 + (ns % 1_000_000_000) as u64
        }
    };
    println!("LDCBF_SOAK_SEED={base}");
    let families = with_reacting(SCRIPTED);
    assert_eq!(families.len(), 17);
    let mut failed = Vec::new();
    for (k, family) in families.iter().enumerate() {
        // Each family its own seeds, so that no two share a draw.
        let start = base + PER_FAMILY * k as u64;
        let a = lidar_batch(family, start, start + PER_FAMILY);
        assert_eq!(a.runs, PER_FAMILY as usize, "{family}");
        if a.contacts_robot != 0 {
            failed.push(format!(
                "{family}: {} robot-caused contacts in seeds {start}..{}; replay one with \
                 `ldcbf-sim run {family} --seed S --set perception='\"lidar\"' \
                 --set planner='\"rrt_star\"' --set delta=0.05`",
                a.contacts_robot,
                start + PER_FAMILY
            ));
        }
    }
    assert!(failed.is_empty(), "LDCBF_SOAK_SEED={base}: {failed:#?}");
}
