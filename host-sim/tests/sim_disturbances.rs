//! Disturbances end to end (`[disturbance]`, `--set disturbance.*`): a moderate
//! push on `simple` is recovered from, the run's files record the push and the
//! true clearance, and a bad disturbance field is refused with a clear error.

use ldcbf_sim::studies::batch::Shard;
use ldcbf_sim::studies::robustness::{
    Condition, RobustnessRequest, cell_stats, default_conditions, is_robustness_dir, merge,
    run_robustness,
};
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
    let md = ldcbf_sim::studies::robustness::markdown(&rep);
    assert!(md.contains("| foot | sigma 5 mm | 0.1 | "), "{md}");
}

#[test]
fn robustness_shards_merge_into_the_whole_study() {
    // 2 conditions x 2 margins x 3 cases = 12 runs, cut short (time_limit 3 s).
    let tmp = tempfile::tempdir().unwrap();
    let request = |out: &str, shard: Shard| {
        let mut req = RobustnessRequest::new();
        req.cases = vec!["simple".parse().unwrap()];
        req.random = 2;
        req.jobs = 2;
        req.deltas = vec![0.0, 0.1];
        req.conditions = vec![
            default_conditions()[0].clone(),
            default_conditions()[5].clone(),
        ];
        req.sets = sets(&[("time_limit", "3")]);
        req.out = Some(tmp.path().join(out));
        req.shard = shard;
        req
    };
    let whole = run_robustness(&request("whole", Shard::ALL)).unwrap();
    assert_eq!(whole.runs.len(), 12);
    let mut dirs = Vec::new();
    for i in 1..=3 {
        let rep = run_robustness(&request(&format!("s{i}"), Shard { index: i, count: 3 })).unwrap();
        assert_eq!(rep.runs.len(), 4);
        assert_eq!(rep.study_runs, 12);
        dirs.push(tmp.path().join(format!("s{i}")));
    }
    let read = |d: &std::path::Path, f: &str| std::fs::read_to_string(d.join(f)).unwrap();
    let but_last_line = |t: String| {
        let mut l: Vec<String> = t.lines().map(String::from).collect();
        l.pop();
        l
    };
    // The merged files are the whole study's (the table but for its last
    // line: runs, jobs, wall time), whatever the order of the directories.
    let m = merge(
        &[dirs[2].clone(), dirs[0].clone(), dirs[1].clone()],
        &tmp.path().join("merged"),
        false,
    )
    .unwrap();
    assert_eq!(m.merged_shards, vec![1, 2, 3]);
    assert_eq!(m.runs, whole.runs);
    let (w, md) = (tmp.path().join("whole"), tmp.path().join("merged"));
    assert_eq!(read(&md, "runs.csv"), read(&w, "runs.csv"));
    assert_eq!(
        but_last_line(read(&md, "table.md")),
        but_last_line(read(&w, "table.md"))
    );
    assert!(
        read(&md, "table.md").contains("12 runs of 12 (merged shards 1, 2, 3 of 3)"),
        "{}",
        read(&md, "table.md")
    );
    // A merged directory merges again with the rest of the study.
    merge(&dirs[..2], &tmp.path().join("m12"), true).unwrap();
    let again = merge(
        &[tmp.path().join("m12"), dirs[2].clone()],
        &tmp.path().join("again"),
        false,
    )
    .unwrap();
    assert_eq!(again.runs, whole.runs);
    // Refused, writing nothing: a missing shard (unless partial results are
    // allowed), a shard twice, another study, a shard without --out.
    let out = tmp.path().join("bad");
    let err = merge(&dirs[..2], &out, false).unwrap_err().to_string();
    assert!(err.contains("incomplete") && err.contains("3/3"), "{err}");
    let err = merge(&[dirs[0].clone(), dirs[0].clone()], &out, true)
        .unwrap_err()
        .to_string();
    assert!(err.contains("given twice"), "{err}");
    let mut other = request("other", Shard { index: 2, count: 3 });
    other.deltas = vec![0.0, 0.05];
    run_robustness(&other).unwrap();
    let err = merge(&[dirs[0].clone(), tmp.path().join("other")], &out, true)
        .unwrap_err()
        .to_string();
    assert!(err.contains("not the same study"), "{err}");
    assert!(!out.exists());
    let mut no_out = request("x", Shard { index: 1, count: 3 });
    no_out.out = None;
    let err = run_robustness(&no_out).unwrap_err().to_string();
    assert!(err.contains("needs --out"), "{err}");
    assert!(is_robustness_dir(&dirs[0]) && !is_robustness_dir(tmp.path()));
}
