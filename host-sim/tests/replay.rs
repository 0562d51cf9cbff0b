//! The recorded cycles of `benches/recorded.rs` are the simulator's: the inputs
//! rebuilt from a run's logs (`ldcbf_sim::studies::replay`), replayed in order through a
//! fresh controller, give back every logged output bit for bit.

use ldcbf_sim::studies::deadline::Case;
use ldcbf_sim::studies::replay::{Recording, record_case};

fn recorded(case: &str) -> Recording {
    let case: Case = case.parse().expect("case");
    let rec = record_case(&case, &[]).expect("the case runs");
    assert!(rec.len() > 100, "{}: only {} cycles", rec.label, rec.len());
    rec
}

#[test]
fn replayed_inputs_reproduce_the_logged_outputs() {
    // Known map (with and without subgoals) and LiDAR (one obstacle list per
    // cycle).
    for case in ["paper", "maze+rrt_star", "random@3", "crowded@0"] {
        let rec = recorded(case);
        rec.verify().unwrap_or_else(|e| panic!("{e:#}"));
        let lidar = case.starts_with("crowded");
        assert_eq!(
            rec.obstacle_sets.len(),
            if lidar { rec.len() } else { 1 },
            "{case}"
        );
        // The stance foot changes with the steps and the time in step cycles
        // through 0, 0.05, ..., 0.35 s (8 cycles per 0.4 s step at 20 Hz).
        let feet: std::collections::HashSet<_> = rec
            .inputs
            .iter()
            .map(|i| (i.stance_foot.x.to_bits(), i.stance_foot.y.to_bits()))
            .collect();
        assert!(feet.len() > rec.len() / 10, "{case}: {} feet", feet.len());
        assert!(rec.inputs.iter().all(|i| i.time_in_step < 0.4 - 1e-9));
    }
}

#[test]
fn a_perturbed_input_is_detected() {
    let original = recorded("paper");
    let mut rec = original.clone();
    let i = rec.len() / 2;
    rec.inputs[i].com_position.x += 1e-6;
    let e = rec.verify().expect_err("perturbed input").to_string();
    assert!(e.contains(&format!("cycle {i}:")), "{e}");
    // A stance foot off by one step is detected too.
    let mut rec = original;
    let j = rec.len() / 3;
    rec.inputs[j].stance_foot = rec.inputs[j.saturating_sub(8)].stance_foot;
    assert!(rec.verify().is_err());
}
