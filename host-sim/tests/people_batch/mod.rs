//! The batch the people tests run: a family's seeds with the LiDAR tracker,
//! planning on the perceived map (`planner = "rrt_star"`) at `delta = 0.05`,
//! as docs/results.md measures the people families.

use ldcbf_sim::plan::Planner;
use ldcbf_sim::sense::Perception;
use ldcbf_sim::studies::batch::{Aggregate, BatchRequest, SeedRange, run_batch};
use ldcbf_sim::world::crowd::families::FAMILIES as REACTING;

/// The scenario names of the scripted families `scripted`, then of every
/// family of people who react (`world/crowd/families.rs`).
pub fn with_reacting(scripted: &[&str]) -> Vec<String> {
    scripted
        .iter()
        .map(|f| f.to_string())
        .chain(REACTING.iter().map(|f| f.replace('_', "-")))
        .collect()
}

/// Seeds `start..end` of `family` (a scenario name) with LiDAR, `rrt_star`
/// and `delta = 0.05`; prints and returns the aggregate.
pub fn lidar_batch(family: &str, start: u64, end: u64) -> Aggregate {
    let tmp = tempfile::tempdir().unwrap();
    let mut req = BatchRequest::new(family, SeedRange { start, end });
    req.perception = Some(Perception::Lidar);
    req.planner = Some(Planner::RrtStar);
    req.sets = vec![("delta".into(), "0.05".into())];
    req.out = Some(tmp.path().join("b"));
    let a = run_batch(&req).unwrap().aggregate;
    println!(
        "{family} seeds {start}..{end}: {} runs, success {}, reached {}, contacts robot {} \
         person {}, min body clearance {:.3} m",
        a.runs, a.success, a.reached, a.contacts_robot, a.contacts_person, a.min_body_clearance
    );
    a
}

/// Runs each `(family, seed)` ([`lidar_batch`], one seed) and asserts the
/// robot moved into no person in any of them; the named regressions of
/// contacts found on unseen seeds.
#[allow(dead_code)] // sim_people_soak draws seeds instead.
pub fn assert_no_robot_caused_contact(cases: &[(&str, u64)]) {
    for &(family, seed) in cases {
        let a = lidar_batch(family, seed, seed + 1);
        assert_eq!(a.runs, 1, "{family} {seed}");
        assert_eq!(a.contacts_robot, 0, "{family} {seed}: {a:?}");
    }
}
