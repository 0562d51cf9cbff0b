//! Tests of the conditions, the statistics and the files of a robustness study.

use super::*;

fn run_of(c: f64, success: bool, fell: bool) -> RobustRun {
    RobustRun {
        condition: 0,
        delta: 0.0,
        group: "random",
        label: "x".into(),
        outcome: if fell {
            Outcome::Diverged
        } else {
            Outcome::GoalReached
        },
        fall_time: fell.then_some(1.0),
        success,
        collision: c < 0.0,
        min_clearance: c,
        steps: 1,
        non_optimal_cycles: 0,
    }
}

#[test]
fn cell_statistics() {
    let runs: Vec<RobustRun> = (0..20)
        .map(|i| run_of(f64::from(i) * 0.01 - 0.015, i >= 2, i == 0))
        .collect();
    let refs: Vec<&RobustRun> = runs.iter().collect();
    let st = cell_stats(&refs);
    assert_eq!(st.runs, 20);
    assert_eq!(st.success, 18);
    assert_eq!(st.collisions, 2);
    assert_eq!(st.collisions_upright, 1);
    assert_eq!(st.falls, 1);
    assert!((st.min_clearance + 0.015).abs() < 1e-12);
    // Upright: the 19 runs from -0.005 m; nearest rank 1 of 19 is the p5.
    assert!((st.min_clearance_upright + 0.005).abs() < 1e-12);
    assert_eq!(st.p5_clearance_upright, st.min_clearance_upright);
    assert!((st.median_clearance_upright - 0.085).abs() < 1e-12);
}

#[test]
fn default_conditions_parse_as_scenario_overrides() {
    for c in default_conditions() {
        let sc = Case::new("simple").load(&c.sets).unwrap();
        assert_eq!(
            sc.disturbance.is_active(sc.config.com_height),
            c.disturbance != "none",
            "{c:?}"
        );
    }
}
