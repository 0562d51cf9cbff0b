//! The `ldcbf-sim` binary: exit codes, messages, files.

mod common;
use common::{fails_in, sim, text};

#[test]
fn list_shows_the_shipped_scenarios() {
    let tmp = tempfile::tempdir().unwrap();
    let o = sim(&["list"], tmp.path());
    assert!(o.status.success());
    let out = text(&o.stdout);
    for name in [
        "simple", "circles", "maze", "paper", "random", "trap", "crowded",
    ] {
        assert!(out.contains(name), "{out}");
    }
}

/// The README's main command, `ldcbf-sim run maze`, with no other argument:
/// finds the shipped scenario (from any directory), writes `out/maze/` with the
/// logs and every figure, and says where they are.
#[test]
fn run_maze_main_command_writes_everything() {
    let tmp = tempfile::tempdir().unwrap();
    let o = sim(&["run", "maze"], tmp.path());
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("out/maze"), "{out}");
    let dir = tmp.path().join("out/maze");
    for f in [
        "summary.json",
        "cycles.csv",
        "footsteps.csv",
        "trajectory.csv",
        "run.mcap",
        "map.png",
        "states.png",
        "frames.png",
        "walk.gif",
    ] {
        let p = dir.join(f);
        assert!(p.is_file(), "{f} missing");
        assert!(std::fs::metadata(&p).unwrap().len() > 100, "{f} empty");
    }
    let png = std::fs::read(dir.join("map.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let gif = std::fs::read(dir.join("walk.gif")).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["scenario"], "maze");
    assert_eq!(summary["collision"], false);
    // The front door shows success: maze plans RRT* subgoals by default.
    assert_eq!(summary["outcome"], "goal_reached", "{summary}");
    assert!(out.contains("goal reached"), "{out}");
    assert!(summary["compute"]["p99_ns"].as_u64().unwrap() > 0);
    // Nothing else (no temporary directory) next to it.
    let entries: Vec<_> = std::fs::read_dir(tmp.path().join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(entries, vec![std::ffi::OsString::from("maze")]);
}

#[test]
fn malformed_scenario_fails_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("bad.toml"),
        "name = \"bad\"\nstart = { x = 0.0, y = 0.0 }\ngoal = [1.0, 1.0]\n\n[[obstacles]]\n\
         vertices = [[0.0, 0.0], [2.0, 0.0], [1.0, 0.5], [2.0, 2.0], [0.0, 2.0]]\n",
    )
    .unwrap();
    let o = sim(&["run", "bad.toml", "--out", "res"], tmp.path());
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert_eq!(err.lines().count(), 1, "one error line: {err}");
    assert!(
        err.starts_with("error: bad.toml:6: field `obstacles[0].vertices`"),
        "{err}"
    );
    assert!(!tmp.path().join("res").exists());
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 1);
}

#[test]
fn bad_arguments_fail() {
    let tmp = tempfile::tempdir().unwrap();
    let o = sim(&["run", "simple", "--set", "nonsense=1"], tmp.path());
    assert!(!o.status.success());
    assert!(text(&o.stderr).contains("nonsense"));
    let o = sim(&["run", "simple", "--mpc-rate", "fast"], tmp.path());
    assert!(!o.status.success());
    assert!(!tmp.path().join("out").exists());
}

/// `run --export-qps DIR` writes one npz per cycle, `qp solve` reads them back
/// and prints one CSV row per file; a missing file fails with its name and
/// prints no partial CSV.
#[test]
fn exported_qps_solve_again() {
    let tmp = tempfile::tempdir().unwrap();
    let o = sim(
        &[
            "run",
            "simple",
            "--no-plots",
            "--out",
            "o",
            "--export-qps",
            "qps",
        ],
        tmp.path(),
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let cycles = std::fs::read_to_string(tmp.path().join("o/cycles.csv")).unwrap();
    let n_cycles = cycles.lines().count() - 1;
    let mut files: Vec<String> = std::fs::read_dir(tmp.path().join("qps"))
        .unwrap()
        .map(|e| e.unwrap().path().display().to_string())
        .collect();
    files.sort();
    assert_eq!(files.len(), n_cycles, "one QP per cycle");
    let mut args = vec!["qp", "solve", "--repeat", "2"];
    args.extend(files.iter().take(5).map(String::as_str));
    let o = sim(&args, tmp.path());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines[0],
        "file,n,m,status,iterations,objective,min_solve_ns,min_prepared_ns,min_ldp_ns,\
         min_ldp_load_ns,ldp_iterations,min_ldp_prepare_ns,path,clarabel_dx,clarabel_dobj"
    );
    assert_eq!(lines.len(), 6);
    assert!(
        lines[1..]
            .iter()
            .all(|l| l.contains(",6,") && l.contains(",solved,") && l.ends_with(",static,,")),
        "{out}"
    );
    // With --check each file is also solved by Clarabel; the two agree.
    let mut args = vec!["qp", "solve", "--check"];
    args.extend(files.iter().take(3).map(String::as_str));
    let o = sim(&args, tmp.path());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    for l in out.lines().skip(1) {
        let c: Vec<&str> = l.split(',').collect();
        let dx: f64 = c[c.len() - 2].parse().unwrap();
        assert!(dx <= 1e-6, "{l}");
    }
    let o = sim(&["qp", "solve", &files[0], "nope.npz"], tmp.path());
    assert!(!o.status.success());
    assert!(o.stdout.is_empty());
    assert!(text(&o.stderr).contains("nope.npz"));
}

/// `run --repeat K`: the same run (every `cycles.csv` column but `compute_ns`
/// equal, the same footsteps), the summary says K; `--repeat 0` is one error
/// line, exit 1, nothing written. No timing is asserted.
#[test]
fn run_repeat_changes_only_the_timings() {
    let tmp = tempfile::tempdir().unwrap();
    for (k, dir) in [("1", "a"), ("3", "b")] {
        let o = sim(
            &["run", "simple", "--no-plots", "--out", dir, "--repeat", k],
            tmp.path(),
        );
        assert!(o.status.success(), "{}", text(&o.stderr));
    }
    let read = |d: &str, f: &str| std::fs::read_to_string(tmp.path().join(d).join(f)).unwrap();
    let without_ns = |csv: &str| -> Vec<String> {
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = header.iter().position(|h| *h == "compute_ns").unwrap();
        lines
            .map(|l| {
                let mut f: Vec<&str> = l.split(',').collect();
                assert!(f[col].parse::<u64>().unwrap() > 0, "{l}");
                f.remove(col);
                f.join(",")
            })
            .collect()
    };
    let (a, b) = (read("a", "cycles.csv"), read("b", "cycles.csv"));
    assert!(a.lines().count() > 100);
    assert_eq!(without_ns(&a), without_ns(&b));
    assert_eq!(read("a", "footsteps.csv"), read("b", "footsteps.csv"));
    assert!(read("a", "summary.json").contains("\"timing_repeats\": 1"));
    assert!(read("b", "summary.json").contains("\"timing_repeats\": 3"));

    let empty = tempfile::tempdir().unwrap();
    fails_in(
        empty.path(),
        &["run", "simple", "--no-plots", "--repeat", "0"],
        &["--repeat must be >= 1"],
    );
}

/// `run --no-mcap` writes the logs without `run.mcap`, and says so.
#[test]
fn no_mcap_skips_run_mcap() {
    let tmp = tempfile::tempdir().unwrap();
    let o = sim(
        &["run", "simple", "--no-plots", "--no-mcap", "--out", "o"],
        tmp.path(),
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(tmp.path().join("o/cycles.csv").is_file());
    assert!(!tmp.path().join("o/run.mcap").exists());
    assert!(!text(&o.stdout).contains("run.mcap"));
}
