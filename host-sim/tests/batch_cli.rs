//! `ldcbf-sim batch`, `merge` and `table` from the command line: files, exit
//! codes, and one clear error line (with nothing written) on bad input.

mod common;
use common::{fails, sim, text};

#[test]
fn bad_batch_arguments_fail_cleanly() {
    fails(&["batch", "--seeds", "0..3", "--shard", "3/2"], "3/2");
    fails(&["batch", "--seeds", "0..3", "--shard", "0/2"], "0/2");
    fails(&["batch", "--seeds", "0..3", "--shard", "two"], "two");
    fails(&["batch", "--seeds", "5..2"], "5..2");
    fails(&["batch", "--seeds", "x..3"], "seed range");
    fails(&["batch", "--seeds", "0..3", "--planner", "astar"], "astar");
    fails(&["batch", "--seeds", "0..3", "--jobs", "0"], "--jobs");
    fails(
        &["batch", "--seeds", "0..3", "--family", "simple"],
        "no [generator]",
    );
    fails(&["batch", "--seeds", "0..3", "--set", "delta=-1"], "delta");
    fails(&["merge", "nope", "--out", "m"], "nope");
    fails(&["table", "nope"], "nope");
}

#[test]
fn batch_shards_merge_and_table_from_the_command_line() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path();
    for (i, dir) in [(1, "s1"), (2, "s2")] {
        let shard = format!("{i}/2");
        let o = sim(
            &[
                "batch",
                "--seeds",
                "0..4",
                "--shard",
                &shard,
                "--jobs",
                "2",
                "--out",
                dir,
                "--planner",
                "rrt_star",
                "--quiet",
            ],
            p,
        );
        assert!(o.status.success(), "{}", text(&o.stderr));
        let csv = std::fs::read_to_string(p.join(dir).join("runs.csv")).unwrap();
        assert_eq!(csv.lines().count(), 3, "header + 2 rows: {csv}");
    }
    // Default output directory when --out is not given.
    let o = sim(&["batch", "--seeds", "7", "--quiet"], p);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(p.join("out/batch-random-none-known/runs.csv").is_file());
    // An incomplete merge fails and writes nothing; the complete one works.
    let o = sim(&["merge", "s1", "--out", "m"], p);
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("--allow-partial"));
    assert!(!p.join("m").exists());
    let o = sim(&["merge", "s1", "s2", "--out", "m"], p);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("4 runs"), "{}", text(&o.stdout));
    let csv = std::fs::read_to_string(p.join("m/runs.csv")).unwrap();
    let seeds: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(seeds, ["0", "1", "2", "3"]);
    let o = sim(&["table", "m", "out/batch-random-none-known"], p);
    assert!(o.status.success());
    let md = text(&o.stdout);
    assert!(md.contains("| | rrt_star / known | none / known |"), "{md}");
    assert!(md.contains("| collisions"), "{md}");
    // No temporary directories left behind.
    let left: Vec<String> = std::fs::read_dir(p)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn robustness_shards_merge_from_the_command_line() {
    // `simple` alone under the nine default conditions, one margin: 9 runs.
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path();
    let study = ["robustness", "simple", "--random", "0", "--delta", "0"];
    let run = |extra: &[&str]| {
        let args: Vec<&str> = study.iter().chain(extra).copied().collect();
        let o = sim(&args, p);
        assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
    };
    run(&["--jobs", "2", "--quiet", "--out", "whole"]);
    run(&["--shard", "1/2", "--jobs", "1", "--quiet", "--out", "s1"]);
    run(&["--shard", "2/2", "--jobs", "1", "--quiet", "--out", "s2"]);
    // Without --out a shard is refused.
    let args: Vec<&str> = study.iter().chain(&["--shard", "1/2"]).copied().collect();
    fails(&args, "needs --out");
    // `merge` recognises robustness directories; the result is the whole study.
    let o = sim(&["merge", "s2", "s1", "--out", "m"], p);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("9 runs of 9 (merged shards 1, 2 of 2)"));
    let read = |d: &str| std::fs::read(p.join(d).join("runs.csv")).unwrap();
    assert_eq!(read("m"), read("whole"));
    // A missing shard: refused, nothing written.
    let o = sim(&["merge", "s1", "--out", "m1"], p);
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("missing shards: 2/2"));
    assert!(!p.join("m1").exists());
}
