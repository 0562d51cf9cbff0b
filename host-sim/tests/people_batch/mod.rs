//! The batch the people tests run: a family's seeds with the LiDAR tracker,
//! planning on the perceived map (`planner = "rrt_star"`) at `delta = 0.05`,
//! as docs/results.md measures the people families.

use ldcbf_sim::plan::Planner;
use ldcbf_sim::sense::Perception;
use ldcbf_sim::studies::batch::{Aggregate, BatchRequest, SeedRange, run_batch};

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
