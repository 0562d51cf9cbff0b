//! Batch evaluation (`ldcbf-sim batch` / `merge` as library calls) on a handful
//! of seeds: rows agree with single runs, shards merge into the whole study,
//! and bad merges are refused without writing anything.

use std::path::PathBuf;

use ldcbf_sim::plan::Planner;
use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sim::{SimOptions, run};
use ldcbf_sim::studies::batch::{
    BatchRequest, RunRow, SeedRange, Shard, merge, read_dir, run_batch,
};
use ldcbf_sim::summarize;

const SEEDS: SeedRange = SeedRange { start: 3, end: 7 };

fn request(out: PathBuf) -> BatchRequest {
    let mut r = BatchRequest::new("random", SEEDS);
    r.jobs = 2;
    r.out = Some(out);
    r
}

/// The deterministic part of a row (not the timings).
fn key(r: &RunRow) -> (u64, String, bool, u64, u64, String) {
    (
        r.seed,
        r.outcome.clone(),
        r.success,
        r.steps,
        r.cycles,
        format!("{:.12} {:.12}", r.sim_time, r.min_com_clearance),
    )
}

#[test]
fn batch_rows_match_single_runs_and_files_are_written() {
    let tmp = tempfile::tempdir().unwrap();
    let rep = run_batch(&request(tmp.path().join("b"))).unwrap();
    assert_eq!(rep.rows.len(), 4);
    assert_eq!(
        rep.rows.iter().map(|r| r.seed).collect::<Vec<_>>(),
        vec![3, 4, 5, 6]
    );
    for f in ["runs.csv", "summary.json", "summary.md"] {
        assert!(rep.out_dir.join(f).is_file(), "{f}");
    }
    let md = std::fs::read_to_string(rep.out_dir.join("summary.md")).unwrap();
    assert!(
        md.contains("success rate") && md.contains("| none / known |"),
        "{md}"
    );
    // Same as `run random --seed S`.
    for row in &rep.rows {
        let sc = load(
            "random",
            &LoadOptions {
                seed: Some(row.seed),
                sets: vec![],
            },
        )
        .unwrap();
        let s = summarize(&run(&sc, SimOptions::default()).unwrap());
        assert_eq!(row.steps, s.steps as u64, "seed {}", row.seed);
        assert_eq!(row.outcome, s.outcome);
        assert_eq!(row.min_com_clearance, s.min_com_clearance.unwrap());
    }
    // The directory reads back to the same rows and aggregate.
    let (meta, agg, rows) = read_dir(&rep.out_dir).unwrap();
    assert_eq!(rows, rep.rows);
    assert_eq!(agg, rep.aggregate);
    assert_eq!(meta.runs, 4);
    assert_eq!(agg.runs, 4);
    assert_eq!(
        agg.success + agg.stuck + agg.timeouts + agg.diverged + (agg.reached - agg.success),
        4
    );
}

#[test]
fn shards_merge_into_the_whole_study() {
    let tmp = tempfile::tempdir().unwrap();
    let mut whole = request(tmp.path().join("whole"));
    whole.planner = Some(Planner::RrtStar);
    let whole = run_batch(&whole).unwrap();
    let mut dirs = Vec::new();
    for i in 1..=2 {
        let mut r = request(tmp.path().join(format!("s{i}")));
        r.planner = Some(Planner::RrtStar);
        r.shard = Shard { index: i, count: 2 };
        r.jobs = 1;
        let rep = run_batch(&r).unwrap();
        assert_eq!(rep.rows.len(), 2);
        dirs.push(rep.out_dir);
    }
    // Interleaved shards: 3, 5 and 4, 6.
    let (_, _, s1) = read_dir(&dirs[0]).unwrap();
    assert_eq!(s1.iter().map(|r| r.seed).collect::<Vec<_>>(), vec![3, 5]);
    // A partial merge is refused unless asked for, and writes nothing.
    let out = tmp.path().join("merged");
    let err = merge(&dirs[..1], &out, false).unwrap_err().to_string();
    assert!(err.contains("incomplete") && err.contains("2/2"), "{err}");
    assert!(!out.exists());
    assert_eq!(merge(&dirs[..1], &out, true).unwrap().rows.len(), 2);
    // The same shard twice is refused.
    let out2 = tmp.path().join("twice");
    let err = merge(&[dirs[0].clone(), dirs[0].clone()], &out2, true)
        .unwrap_err()
        .to_string();
    assert!(err.contains("given twice"), "{err}");
    assert!(!out2.exists());
    // Shards of another study are refused.
    let other = run_batch(&request(tmp.path().join("other"))).unwrap();
    let err = merge(&[dirs[0].clone(), other.out_dir], &out2, true)
        .unwrap_err()
        .to_string();
    assert!(err.contains("not the same study"), "{err}");
    // A missing directory is a clear error.
    let err = merge(&[dirs[0].clone(), tmp.path().join("nope")], &out2, true)
        .unwrap_err()
        .to_string();
    assert!(err.contains("nope") && err.contains("no such"), "{err}");
    assert!(!out2.exists());
    // The full merge equals the single-machine run.
    let m = merge(&dirs, &tmp.path().join("merged-all"), false).unwrap();
    assert_eq!(m.meta.merged_shards, vec![1, 2]);
    assert_eq!(
        m.rows.iter().map(key).collect::<Vec<_>>(),
        whole.rows.iter().map(key).collect::<Vec<_>>()
    );
    assert_eq!(m.aggregate.success, whole.aggregate.success);
    assert_eq!(m.aggregate.mean_steps, whole.aggregate.mean_steps);
}

#[test]
fn a_family_without_generator_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let mut r = BatchRequest::new("simple", SEEDS);
    r.out = Some(tmp.path().join("x"));
    let err = run_batch(&r).unwrap_err().to_string();
    assert!(err.contains("no [generator]"), "{err}");
    assert!(!tmp.path().join("x").exists());
}
