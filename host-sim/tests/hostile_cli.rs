//! Hostile input to `ldcbf-sim` (docs/cli-errors.md, "Limits"): recursion
//! and size limits, unbounded resources, output locations found unusable only
//! late, silently wrong values, misleading messages, and signals. Each bad
//! input ends in one short `error:` line, exit status 1 (2 for clap's argument
//! errors, 128 + signal when stopped), and nothing written.

mod common;
use common::{fails_in, sim, text};

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The shipped `simple` scenario, as text.
fn simple_toml() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/simple.toml"))
        .unwrap()
}

/// A fresh directory holding `simple.toml` with `from` replaced by `to`.
fn dir_with(from: &str, to: &str) -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    let text = simple_toml();
    assert!(text.contains(from), "{from}");
    std::fs::write(tmp.path().join("s.toml"), text.replacen(from, to, 1)).unwrap();
    tmp
}

/// `run s.toml --no-plots ARGS` on the file of [`dir_with`] fails with one
/// line containing every needle, at most `max_len` bytes long.
fn run_fails(from: &str, to: &str, args: &[&str], needles: &[&str]) -> String {
    let tmp = dir_with(from, to);
    let mut all = vec!["run", "s.toml", "--no-plots"];
    all.extend_from_slice(args);
    let line = fails_in(tmp.path(), &all, needles);
    assert!(line.len() < 600, "a short line: {} bytes", line.len());
    line
}

#[test]
fn recursion_and_size_limits() {
    let parts = vec!["a"; 20_000].join(".");
    run_fails("", "", &["--set", &format!("{parts}=1")], &["too long"]);
    let nine = ["a"; 9].join(".");
    run_fails("", "", &["--set", &format!("{nine}=1")], &["dotted parts"]);
    let deep = format!("goal={}{}", "[".repeat(20_000), "]".repeat(20_000));
    run_fails("", "", &["--set", &deep], &["not a TOML list or table"]);
    // Deep values in the file: the TOML parser's own depth limit.
    let deep_file = format!("goal = {}1{}", "{a=".repeat(5_000), "}".repeat(5_000));
    run_fails("goal = [5.0, 5.0]", &deep_file, &[], &["field `goal`"]);
    // A 100 kB key (near the kernel's limit on one argument) is not echoed
    // whole.
    let long = format!("{}=1", "k".repeat(100_000));
    run_fails("", "", &["--set", &long], &["bytes in all", "too long"]);
}

#[test]
fn exact_lengths_and_absurd_magnitudes_name_the_field() {
    let g = "goal = [5.0, 5.0]";
    run_fails(
        g,
        "goal = [5.0, 5.0, 7.0]",
        &[],
        &["field `goal`", "exactly 2"],
    );
    run_fails("", "", &["--set", "goal=[5,5,7]"], &["`goal`", "exactly 2"]);
    run_fails(
        "center = [2.6, 2.4]",
        "center = [2.6]",
        &[],
        &["obstacles[0]", "exactly 2"],
    );
    run_fails(
        "",
        "",
        &["--set", "goal=[1e300,5]"],
        &["`goal[0]`", "out of range"],
    );
    run_fails(
        "",
        "",
        &["--set", "gravity=1e308"],
        &["`controller.gravity`", "out of range"],
    );
    // A start heading within the range of numbers but not an angle: the
    // first turn took it past the controller's input range, and the run
    // ended as "diverged" after 0.45 s.
    run_fails(
        "heading = 0.0 }",
        "heading = 1e6 }",
        &[],
        &["field `start`", "heading 1000000 rad"],
    );
    // Within the range but an overflowing step map: every input is named.
    run_fails(
        "",
        "",
        &["--set", "gravity=1e6", "--set", "step_duration=1"],
        &["controller.step_duration", "gravity 1000000"],
    );
}

#[test]
fn messages_name_the_real_problem() {
    let bow = "[[obstacles]]\nvertices = [[1.0, 4.0], [2.0, 5.0], [2.0, 4.0], [1.0, 5.0]]\n\n[[obstacles]]";
    let line = run_fails(
        "[[obstacles]]",
        bow,
        &[],
        &["obstacles[0]", "self-intersecting"],
    );
    assert!(!line.contains("collinear"), "{line}");
    let tmp = tempfile::tempdir().unwrap();
    fails_in(
        tmp.path(),
        &["run", "/dev/zero"],
        &["/dev/zero", "not a regular file"],
    );
}

#[test]
fn unbounded_resources_are_refused_or_capped() {
    let tmp = tempfile::tempdir().unwrap();
    for args in [
        &["batch", "--seeds", "0..18446744073709551615", "--quiet"][..],
        &["batch", "--seeds", "0..1000001", "--quiet"][..],
        &["deadline", "--random", "18446744073709551615"][..],
        &["robustness", "--random", "1000001"][..],
    ] {
        let o = sim(args, tmp.path());
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("1000000"), "{args:?}: {err}");
    }
    fails_in(
        tmp.path(),
        &["qp", "solve", "x.npz", "--max-iter", "0"],
        &["--max-iter"],
    );
    fails_in(
        tmp.path(),
        &["qp", "solve", "x.npz", "--repeat", "0"],
        &["--repeat"],
    );
    // Timings of each control cycle: 100,000,000 ran for hours.
    fails_in(
        tmp.path(),
        &["run", "simple", "--no-plots", "--repeat", "10001"],
        &["--repeat", "at most 10000", "got 10001"],
    );
    fails_in(
        tmp.path(),
        &["deadline", "--random", "1", "--repeat", "10001"],
        &["--repeat", "at most 10000"],
    );
    // 100,000 threads asked for: lowered, with a note, and the batch runs.
    let o = sim(
        &[
            "batch", "--seeds", "0", "--jobs", "100000", "--quiet", "--out", "b",
        ],
        tmp.path(),
    );
    let err = text(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("--jobs 100000 lowered to"), "{err}");
}

#[test]
fn output_locations_are_checked_first_and_links_respected() {
    use std::os::unix::fs::symlink;
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir(d.join("good")).unwrap();
    symlink("nowhere", d.join("dangling")).unwrap();
    std::fs::create_dir(d.join("real")).unwrap();
    symlink("real", d.join("link")).unwrap();
    for (out, needle) in [
        ("good/.", "no usable last component"),
        ("good/..", "no usable last component"),
        ("dangling", "symbolic link to nowhere"),
    ] {
        for cmd in [
            &["run", "simple", "--no-plots"][..],
            &["batch", "--seeds", "0"][..],
        ] {
            let mut args = cmd.to_vec();
            args.extend(["--out", out]);
            let o = sim(&args, d);
            let err = text(&o.stderr);
            assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
            assert!(err.contains(needle), "{args:?}: {err}");
            let names: Vec<_> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().into_string().unwrap())
                .collect();
            assert_eq!(names.len(), 4, "nothing created: {names:?}");
        }
    }
    // Written through a link to a directory; the link stays a link.
    let o = sim(&["run", "simple", "--no-plots", "--out", "link"], d);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let meta = std::fs::symlink_metadata(d.join("link")).unwrap();
    assert!(meta.file_type().is_symlink(), "the link was replaced");
    assert!(d.join("real/summary.json").is_file());
}

/// Starts `args` in `dir`, waits for a `.*.tmp-*` directory (the run is under
/// way), sends `signal` and returns the exit code.
fn interrupted(dir: &Path, args: &[&str], signal: &str) -> Option<i32> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ldcbf-sim"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let has_tmp = || {
        std::fs::read_dir(dir)
            .unwrap()
            .any(|e| e.unwrap().file_name().to_string_lossy().contains(".tmp-"))
    };
    while !has_tmp() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(has_tmp(), "{args:?}: no temporary directory appeared");
    let pid = child.id().to_string();
    assert!(
        Command::new("kill")
            .args([signal, &pid])
            .status()
            .unwrap()
            .success()
    );
    child.wait().unwrap().code()
}

#[test]
fn signals_stop_a_run_and_leave_nothing_behind() {
    for (signal, code) in [("-INT", 130), ("-TERM", 143)] {
        let tmp = tempfile::tempdir().unwrap();
        // A goal 1.2 km away: minutes of walking unless stopped.
        let args = [
            "run",
            "simple",
            "--no-plots",
            "--out",
            "o",
            "--set",
            "goal=[900,900]",
            "--set",
            "time_limit=1e5",
            "--set",
            "stuck_window=0",
        ];
        assert_eq!(interrupted(tmp.path(), &args, signal), Some(code));
        let left: Vec<_> = std::fs::read_dir(tmp.path()).unwrap().collect();
        assert!(left.is_empty(), "{signal}: left {left:?}");
    }
}
