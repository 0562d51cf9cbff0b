//! Tests of the summary and the output directory.

use super::*;

#[test]
fn nearest_rank_percentiles() {
    let v: Vec<u64> = (1..=100).collect();
    assert_eq!(percentile(&v, 50.0), 50);
    assert_eq!(percentile(&v, 99.0), 99);
    assert_eq!(percentile(&v, 100.0), 100);
    assert_eq!(percentile(&[7], 99.0), 7);
    assert_eq!(percentile(&[], 50.0), 0);
    let s = compute_stats(&[5, 1, 3]);
    assert_eq!((s.p50_ns, s.max_ns), (3, 5));
}

#[test]
fn output_dir_is_removed_unless_committed() {
    let base = std::env::temp_dir().join(format!("ldcbf-outdir-{}", std::process::id()));
    let target = base.join("run");
    {
        let d = OutputDir::create(&target).unwrap();
        std::fs::write(d.path().join("x"), "1").unwrap();
    }
    assert!(!target.exists());
    assert!(!base.exists(), "the parent made for it is gone too");
    let d = OutputDir::create(&target).unwrap();
    std::fs::write(d.path().join("x"), "1").unwrap();
    let p = d.commit().unwrap();
    assert!(p.join("x").is_file());
    // A directory that is not a previous run is never replaced.
    assert!(OutputDir::create(&target).is_err());
    std::fs::write(target.join("summary.json"), "{}").unwrap();
    let d = OutputDir::create(&target).unwrap();
    std::fs::write(d.path().join("y"), "2").unwrap();
    let p = d.commit().unwrap();
    assert!(p.join("y").is_file() && !p.join("x").exists());
    assert_eq!(std::fs::read_dir(&base).unwrap().count(), 1);
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn failed_outputs_leave_no_parent_and_files_are_refused() {
    let base = tempfile::tempdir().unwrap();
    let b = base.path();
    // Parents made for an output that is never committed are removed again.
    {
        let d = OutputDir::create(&b.join("a/b/c")).unwrap();
        std::fs::write(d.path().join("x"), "1").unwrap();
    }
    assert_eq!(std::fs::read_dir(b).unwrap().count(), 0);
    // A parent that already existed stays.
    std::fs::create_dir(b.join("keep")).unwrap();
    drop(OutputDir::create(&b.join("keep/new/run")).unwrap());
    assert_eq!(std::fs::read_dir(b.join("keep")).unwrap().count(), 0);
    // Files are never replaced, nor used as parents; nothing is created.
    std::fs::write(b.join("f"), "data").unwrap();
    for (p, msg) in [
        ("f", "is a file"),
        ("f/x", "is a file, not a directory"),
        ("keep/..", "no usable last component"),
    ] {
        let e = OutputDir::create(&b.join(p)).unwrap_err().to_string();
        assert!(e.contains(msg), "{p}: {e}");
        assert!(OutputDir::preflight(&b.join(p)).is_err());
    }
    assert_eq!(std::fs::read(b.join("f")).unwrap(), b"data");
    assert_eq!(std::fs::read_dir(b).unwrap().count(), 2);
    // A previous QP export (only cycle_NNNNN.npz) is replaced; with another
    // file in it, it is not.
    std::fs::create_dir(b.join("qps")).unwrap();
    std::fs::write(b.join("qps/cycle_00001.npz"), "").unwrap();
    OutputDir::preflight(&b.join("qps")).unwrap();
    std::fs::write(b.join("qps/notes.txt"), "").unwrap();
    assert!(OutputDir::preflight(&b.join("qps")).is_err());
}

/// The summary keeps the disturbance log only when something was disturbed.
#[test]
fn summary_has_a_disturbance_log_only_with_a_disturbance() {
    use crate::scenario::{LoadOptions, load};
    use crate::sim::{SimOptions, run};
    let go = |sets: &[(&str, &str)]| {
        let mut all = vec![("time_limit", "2.0")];
        all.extend_from_slice(sets);
        let sc = load("simple", &LoadOptions::with_sets(&all)).unwrap();
        summarize(&run(&sc, SimOptions::default()).unwrap())
    };
    let zero = go(&[
        ("disturbance.seed", "9"),
        ("disturbance.push_time", "1.0"),
        ("disturbance.push_period", "0.5"),
        ("disturbance.plant_com_height", "1.0"),
        ("disturbance.foot_sigma", "0.0"),
        ("disturbance.noise_position", "0.0"),
    ]);
    assert!(zero.disturbance.is_none());
    let pushed = go(&[
        ("disturbance.push_time", "1.234"),
        ("disturbance.push_forward", "0.1"),
        ("disturbance.push_lateral", "0.3"),
    ]);
    assert_eq!(pushed.disturbance.unwrap().pushes.len(), 1);
}
