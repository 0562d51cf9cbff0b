//! A malformed scenario or an unusable output location gives one clear error
//! (file, field, line; or the option and path) and leaves no output directory
//! behind.

use std::path::Path;

use ldcbf_sim::{RunRequest, execute_run};

const GOOD: &str = r#"name = "t"
start = { x = 0.0, y = 0.0 }
goal = [3.0, 0.0]
time_limit = 5.0

[[obstacles]]
vertices = [[1.0, 1.0], [2.0, 1.0], [1.5, 2.0]]

[[obstacles]]
vertices = [[1.0, -1.0], [2.0, -1.0], [1.5, -2.0]]
"#;

/// Runs `text` as a scenario file with output in `<tmp>/out`; returns the error
/// text and asserts that nothing was written.
fn run_bad(text: &str) -> String {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("bad.toml");
    std::fs::write(&file, text).unwrap();
    let out = tmp.path().join("out");
    let mut req = RunRequest::new(file.to_str().unwrap());
    req.out = Some(out.clone());
    req.plots = false;
    let err = execute_run(&req).expect_err("malformed scenario must fail");
    let msg = format!("{err:#}");
    assert!(!out.exists(), "output directory left behind");
    let left: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("bad.toml")], "{left:?}");
    assert!(
        msg.contains(file.to_str().unwrap()),
        "names the file: {msg}"
    );
    msg
}

#[test]
fn good_file_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("good.toml");
    std::fs::write(&file, GOOD).unwrap();
    let mut req = RunRequest::new(file.to_str().unwrap());
    req.out = Some(tmp.path().join("out"));
    req.plots = false;
    let rep = execute_run(&req).unwrap();
    for f in [
        "summary.json",
        "cycles.csv",
        "footsteps.csv",
        "trajectory.csv",
    ] {
        assert!(rep.out_dir.join(f).is_file(), "{f}");
    }
    assert!(Path::new(&rep.out_dir).ends_with("out"));
}

#[test]
fn non_convex_obstacle_is_named_with_its_line() {
    let text = GOOD.replace(
        "vertices = [[1.0, -1.0], [2.0, -1.0], [1.5, -2.0]]",
        "vertices = [[0.0, 0.0], [2.0, 0.0], [1.0, 0.5], [2.0, 2.0], [0.0, 2.0]]",
    );
    let msg = run_bad(&text);
    assert!(msg.contains(":10:"), "line 10: {msg}");
    assert!(msg.contains("obstacles[1]"), "{msg}");
    assert!(msg.contains("convex"), "{msg}");
}

#[test]
fn syntax_error_names_line() {
    let msg = run_bad(&GOOD.replace("goal = [3.0, 0.0]", "goal = [3.0, 0.0"));
    assert!(msg.contains(":4:") && msg.contains("`goal`"), "{msg}");
}

#[test]
fn wrong_type_names_field_and_line() {
    let msg = run_bad(&GOOD.replace("time_limit = 5.0", "time_limit = \"soon\""));
    assert!(msg.contains(":4:") && msg.contains("time_limit"), "{msg}");
}

#[test]
fn unknown_field_is_rejected() {
    let msg = run_bad(&GOOD.replace("time_limit = 5.0", "time_limt = 5.0"));
    assert!(msg.contains(":4:") && msg.contains("time_limt"), "{msg}");
}

#[test]
fn bad_controller_override_is_named() {
    let msg = run_bad(&GOOD.replace(
        "time_limit = 5.0",
        "time_limit = 5.0\n[controller]\ngamma = 1.5",
    ));
    assert!(
        msg.contains("controller.gamma") && msg.contains(":6:"),
        "{msg}"
    );
}

#[test]
fn unknown_planner_is_rejected_clearly() {
    let msg = run_bad(&GOOD.replace("time_limit = 5.0", "time_limit = 5.0\nplanner = \"rrt\""));
    assert!(msg.contains("planner") && msg.contains(":5:"), "{msg}");
}

#[test]
fn bad_planner_and_lidar_settings_are_named() {
    let msg = run_bad(&GOOD.replace(
        "time_limit = 5.0",
        "time_limit = 5.0\n[rrt_star]\nmargin = -1.0",
    ));
    assert!(
        msg.contains("rrt_star.margin") && msg.contains(":6:"),
        "{msg}"
    );
    let msg = run_bad(&GOOD.replace(
        "time_limit = 5.0",
        "time_limit = 5.0\n[lidar]\nrays = 360\neps = 0.0",
    ));
    assert!(msg.contains("lidar.eps") && msg.contains(":7:"), "{msg}");
}

/// An unusable output location fails before the simulation, names the option
/// and the path, and creates nothing (not even a parent directory).
#[test]
fn unusable_output_locations_fail_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("good.toml");
    std::fs::write(&file, GOOD).unwrap();
    let taken = tmp.path().join("taken");
    std::fs::write(&taken, "x").unwrap();
    let new = tmp.path().join("new/res");
    let cases: [(Option<std::path::PathBuf>, Option<std::path::PathBuf>, &str); 4] = [
        (Some(taken.clone()), None, "is a file, not a directory"),
        (Some(taken.join("sub")), None, "taken is a file"),
        (Some(new.clone()), Some(taken.clone()), "--export-qps"),
        (
            Some(new.clone()),
            Some(new.join("qps")),
            "apart from the output directory",
        ),
    ];
    for (out, qps, needle) in cases {
        let mut req = RunRequest::new(file.to_str().unwrap());
        req.out = out;
        req.export_qps = qps;
        req.plots = false;
        let msg = format!("{:#}", execute_run(&req).expect_err("must fail"));
        assert!(msg.contains(needle), "{msg}");
        let mut left: Vec<_> = std::fs::read_dir(tmp.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        assert_eq!(left, ["good.toml", "taken"], "{msg}");
        assert_eq!(std::fs::read(&taken).unwrap(), b"x");
    }
}
