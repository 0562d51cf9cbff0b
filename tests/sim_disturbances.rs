//! Disturbances end to end (`[disturbance]`, `--set disturbance.*`): a moderate
//! push on `simple` is recovered from, the run's files record the push and the
//! true clearance, and a bad disturbance field is refused with a clear error.

use ldcbf_sim::robustness::{Condition, RobustnessRequest, cell_stats, run_robustness};
use ldcbf_sim::{RunRequest, execute_run};

fn sets(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

#[test]
fn a_moderate_push_on_simple_is_recovered_from() {
    let tmp = tempfile::tempdir().unwrap();
    let mut req = RunRequest::new("simple");
    req.out = Some(tmp.path().join("out"));
    req.plots = false;
    req.gif = false;
    // 0.1 m/s to the left of the heading, 3.01 s in (mid-walk, between cycles).
    req.sets = sets(&[
        ("disturbance.push_time", "3.01"),
        ("disturbance.push_lateral", "0.1"),
    ]);
    let rep = execute_run(&req).unwrap();
    let s = &rep.summary;
    assert_eq!(s.outcome, "goal_reached");
    assert!(
        s.success,
        "collision: min clearance {:?}",
        s.min_com_clearance
    );
    let clearance = s.min_com_clearance.expect("simple has obstacles");
    assert!(clearance.is_finite() && clearance >= 0.0, "{clearance}");
    let d = s.disturbance.as_ref().expect("a push is a disturbance");
    assert_eq!(d.pushes.len(), 1);
    assert_eq!(d.pushes[0].tick, 3010);
    let dv = d.pushes[0].delta_v;
    assert!(((dv[0] * dv[0] + dv[1] * dv[1]).sqrt() - 0.1).abs() < 1e-12);
    // summary.json on disk carries the push event and the true clearance.
    let json = std::fs::read_to_string(rep.out_dir.join("summary.json")).unwrap();
    assert!(
        json.contains("\"pushes\": [") && json.contains("\"tick\": 3010"),
        "{json}"
    );
    assert!(
        json.contains(&format!("\"min_com_clearance\": {clearance}")),
        "{json}"
    );
    // The undisturbed walk is a different one (the push mattered).
    let mut base = RunRequest::new("simple");
    base.out = Some(tmp.path().join("base"));
    base.plots = false;
    base.gif = false;
    let b = execute_run(&base).unwrap();
    assert!(b.summary.disturbance.is_none());
    assert_ne!(b.summary.min_com_clearance, s.min_com_clearance);
}

#[test]
fn a_bad_disturbance_field_is_refused_by_name() {
    for (k, v, field) in [
        ("disturbance.foot_sigma", "-0.01", "disturbance.foot_sigma"),
        (
            "disturbance.noise_position",
            "inf",
            "disturbance.noise_position",
        ),
        ("disturbance.push_forward", "0.2", "disturbance.push_time"),
        ("disturbance.pushh_time", "1.0", "pushh_time"),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let mut req = RunRequest::new("simple");
        req.out = Some(tmp.path().join("out"));
        req.plots = false;
        req.sets = sets(&[(k, v)]);
        let err = format!("{:#}", execute_run(&req).expect_err(k));
        assert!(err.contains(field), "{k}={v}: {err}");
        assert!(!tmp.path().join("out").exists());
    }
}

#[test]
fn robustness_study_counts_a_small_grid() {
    // Two short cases, one disturbance, two margins: the machinery end to end.
    let mut req = RobustnessRequest::new();
    req.cases = vec!["simple".parse().unwrap()];
    req.random = 1;
    req.jobs = 2;
    req.deltas = vec![0.0, 0.1];
    req.conditions = vec![Condition {
        disturbance: "foot".into(),
        magnitude: "sigma 5 mm".into(),
        sets: sets(&[("disturbance.foot_sigma", "0.005")]),
    }];
    let rep = run_robustness(&req).unwrap();
    assert_eq!(rep.runs.len(), 4);
    for d in [0.0, 0.1] {
        let cell: Vec<_> = rep.runs.iter().filter(|r| r.delta == d).collect();
        let st = cell_stats(&cell);
        assert_eq!(st.runs, 2);
        assert!(st.min_clearance.is_finite());
        assert_eq!(
            st.success
                + st.falls
                + st.stuck
                + st.time_limit
                + cell
                    .iter()
                    .filter(|r| !r.success && r.fall_time.is_none() && r.collision)
                    .filter(|r| r.outcome == ldcbf_sim::Outcome::GoalReached)
                    .count(),
            2
        );
    }
    let md = ldcbf_sim::robustness::markdown(&rep);
    assert!(md.contains("| foot | sigma 5 mm | 0.1 | "), "{md}");
}
