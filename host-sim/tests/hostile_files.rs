//! Hostile input to `ldcbf-sim`, second round (docs/cli-errors.md, "Hostile
//! input"): files that are not regular files, `.npy` headers that only look
//! right, npz files that decompress to more than memory, tampered study
//! shards, planning settings that would run for hours, people who walk off
//! the coordinate range, map settings under which the frontier cannot hold
//! the robot, and output names at the length limit. Each ends in one `error:`
//! line naming the file and the field with exit status 1 and nothing written,
//! or in correct behaviour.

mod common;
use common::{fails_in, npy, npy_f64, sim, small_qp, text, zip};

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The shipped `simple` scenario, as text.
fn simple_toml() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/simple.toml"))
        .unwrap()
}

/// Runs `args` in `dir` and waits at most `limit`; kills the command and
/// fails the test if it is still running then (a hang is a failure, not a
/// test that never ends). Returns the exit code and stderr.
fn run_bounded(dir: &Path, args: &[&str], limit: Duration) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_ldcbf-sim"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("{args:?} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().unwrap();
    (o.status.code(), text(&o.stderr))
}

/// Makes a FIFO at `path`.
fn mkfifo(path: &Path) {
    assert!(Command::new("mkfifo").arg(path).status().unwrap().success());
}

#[test]
fn fifos_and_devices_are_refused_before_they_are_opened() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    mkfifo(&d.join("s.toml"));
    mkfifo(&d.join("f.csv"));
    mkfifo(&d.join("f.npz"));
    std::fs::create_dir(d.join("b")).unwrap();
    mkfifo(&d.join("b/summary.json"));
    std::fs::write(d.join("b/runs.csv"), "x\n").unwrap();
    for (args, file) in [
        (&["run", "s.toml", "--no-plots"][..], "s.toml"),
        (&["deadline", "--instructions", "f.csv"][..], "f.csv"),
        (&["qp", "solve", "f.npz"][..], "f.npz"),
        (&["table", "b"][..], "b/summary.json"),
        (&["merge", "b", "--out", "m"][..], "b/summary.json"),
        (&["run", "/dev/zero", "--no-plots"][..], "/dev/zero"),
        (&["qp", "solve", "/dev/zero"][..], "/dev/zero"),
        (
            &["deadline", "--instructions", "/dev/zero"][..],
            "/dev/zero",
        ),
    ] {
        let (code, err) = run_bounded(d, args, Duration::from_secs(60));
        assert_eq!(code, Some(1), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("error: "), "{args:?}: {err}");
        assert!(err.contains(file), "{args:?}: {err}");
        assert!(err.contains("not a regular file"), "{args:?}: {err}");
        assert!(!d.join("m").exists());
    }
}

/// A valid npz QP (`small_qp`) with member `P` replaced by `p`.
fn npz_with_p(p: Vec<u8>) -> Vec<u8> {
    let qp = small_qp();
    zip(&[
        ("P.npy", p),
        ("q.npy", npy_f64(&[6], &qp.q)),
        ("G.npy", npy_f64(&[1, 6], &qp.G)),
        ("h.npy", npy_f64(&[1], &qp.h)),
    ])
}

/// The header of a `.npy` array written by hand: `dict` as the header text.
fn npy_raw(dict: &str, data: &[u8]) -> Vec<u8> {
    let mut h = dict.to_string();
    while !(10 + h.len() + 1).is_multiple_of(64) {
        h.push(' ');
    }
    h.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend_from_slice(&u16::try_from(h.len()).unwrap().to_le_bytes());
    b.extend_from_slice(h.as_bytes());
    b.extend_from_slice(data);
    b
}

#[test]
fn npy_headers_are_read_as_numpy_reads_them() {
    let qp = small_qp();
    let data: Vec<u8> = qp.P.iter().flat_map(|v| v.to_le_bytes()).collect();
    // The numpy header of the same array still solves.
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("ok.npz"),
        npz_with_p(npy("<f8", false, "(6, 6)", &data)),
    )
    .unwrap();
    let o = sim(&["qp", "solve", "ok.npz"], tmp.path());
    assert!(o.status.success(), "{}", text(&o.stderr));
    for (dict, needle) in [
        // A key inside a string value: the old text search read it.
        (
            "{'descr': \"<f8', 'fortran_order': True, 'x': '\", 'fortran_order': False, 'shape': (6, 6), }",
            "is not float64",
        ),
        (
            "{'descr': '<f8', 'fortran_order': True, 'fortran_order': False, 'shape': (6, 6), }",
            "given twice",
        ),
        (
            "{'descr': '<f8', 'fortran_order': False, 'shape': (6, 6), 'shape': (6, 6), }",
            "given twice",
        ),
        (
            "{'descr': '<f8', 'fortran_order': False, 'shape': (6, 6), 'extra': 'x', }",
            "unexpected key",
        ),
        ("{'descr': '<f8', 'shape': (6, 6), }", "no `fortran_order`"),
        (
            "{'descr': '<f8', 'fortran_order': False, 'shape': (6, 6), } junk",
            "text after the dict",
        ),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(tmp.path().join("f.npz"), npz_with_p(npy_raw(dict, &data))).unwrap();
        fails_in(
            tmp.path(),
            &["qp", "solve", "f.npz"],
            &["f.npz: key `P`", needle],
        );
    }
}

#[test]
fn npz_files_cannot_make_the_reader_allocate_more_than_the_caps() {
    let tmp = tempfile::tempdir().unwrap();
    // A member that declares 4 GiB decompressed: refused from the zip
    // directory, before anything is read.
    let mut bytes = npz_with_p(npy_f64(&[6, 6], &small_qp().P));
    let cd = bytes
        .windows(4)
        .position(|w| w == 0x0201_4b50u32.to_le_bytes())
        .unwrap();
    bytes[cd + 24..cd + 28].copy_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(tmp.path().join("big.npz"), &bytes).unwrap();
    fails_in(
        tmp.path(),
        &["qp", "solve", "big.npz"],
        &["big.npz: key `P`", "more than the", "67108864"],
    );
    // 1001 variables: over the problem-size cap, refused before solving.
    let n = 1001;
    let mut p = vec![0.0; n * n];
    for i in 0..n {
        p[i * n + i] = 1.0;
    }
    std::fs::write(
        tmp.path().join("wide.npz"),
        zip(&[
            ("P.npy", npy_f64(&[n, n], &p)),
            ("q.npy", npy_f64(&[n], &vec![0.0; n])),
        ]),
    )
    .unwrap();
    fails_in(
        tmp.path(),
        &["qp", "solve", "wide.npz"],
        &["wide.npz: key `P`", "1001 variables", "1000"],
    );
}

/// A batch of seeds `0..4`, shard 1/2 (seeds 0 and 2), in `dir/b`; returns
/// its `summary.json` and `runs.csv`.
fn shard(dir: &Path) -> (String, String) {
    let o = sim(
        &[
            "batch", "--seeds", "0..4", "--shard", "1/2", "--out", "b", "--quiet", "--jobs", "1",
        ],
        dir,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let read = |f: &str| std::fs::read_to_string(dir.join("b").join(f)).unwrap();
    (read("summary.json"), read("runs.csv"))
}

#[test]
fn tampered_shards_are_refused_by_table_and_merge() {
    let tmp = tempfile::tempdir().unwrap();
    let (summary, runs) = shard(tmp.path());
    std::fs::remove_dir_all(tmp.path().join("b")).unwrap();
    let rows: Vec<&str> = runs.lines().collect();
    assert_eq!(rows.len(), 3, "{runs}");
    assert!(rows[2].starts_with("2,"), "{runs}");
    let with_row2 = |row: String| format!("{}\n{}\n{row}\n", rows[0], rows[1]);
    // A row that claims success and a collision no person caused.
    let cols: Vec<&str> = rows[2].split(',').collect();
    let mut both = cols.clone();
    (both[2], both[3]) = ("1", "1");
    let both = both.join(",");
    let cases: Vec<(String, String, Vec<&str>)> = vec![
        (
            summary.clone(),
            with_row2(rows[2].replacen("2,", "100,", 1)),
            vec!["b/runs.csv:3", "seed 100 is outside the study's seeds 0..4"],
        ),
        (
            summary.clone(),
            with_row2(rows[2].replacen("2,", "1,", 1)),
            vec!["b/runs.csv:3", "seed 1 is not in shard 1/2"],
        ),
        (
            summary.clone(),
            with_row2(rows[2].replacen("2,", "0,", 1)),
            vec!["b/runs.csv:3", "seed 0 appears twice"],
        ),
        (
            summary.clone(),
            with_row2(both),
            vec!["b/runs.csv:3", "success"],
        ),
        (
            summary.replacen("\"index\": 1", "\"index\": 0", 1),
            runs.clone(),
            vec!["b/summary.json", "out of range"],
        ),
        (
            summary.replacen("\"index\": 1", "\"index\": 5", 1),
            runs.clone(),
            vec!["b/summary.json", "out of range"],
        ),
        (
            summary.replacen("\"end\": 4", "\"end\": 0", 1),
            runs.clone(),
            vec!["b/summary.json", "empty seed range"],
        ),
        // One seed of the shard missing, the row count edited to match.
        (
            summary.replacen("\"runs\": 2", "\"runs\": 1", 1),
            format!("{}\n{}\n", rows[0], rows[1]),
            vec![
                "b/runs.csv",
                "1 rows, but shard 1/2 of seeds 0..4 has 2 seeds",
            ],
        ),
    ];
    for (s, r, needles) in &cases {
        assert!(s != &summary || r != &runs, "{needles:?}: no change");
        let case = tempfile::tempdir().unwrap();
        std::fs::create_dir(case.path().join("b")).unwrap();
        std::fs::write(case.path().join("b/summary.json"), s).unwrap();
        std::fs::write(case.path().join("b/runs.csv"), r).unwrap();
        fails_in(case.path(), &["table", "b"], needles);
        fails_in(
            case.path(),
            &["merge", "b", "--out", "m", "--allow-partial"],
            needles,
        );
    }
}

#[test]
fn planning_is_bounded_and_stops_at_once_on_a_signal() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let mut child = Command::new(env!("CARGO_BIN_EXE_ldcbf-sim"))
        .args([
            "run",
            "large-map",
            "--no-plots",
            "--out",
            "o",
            "--set",
            "planner=\"rrt_star\"",
            "--set",
            "rrt_star.iterations=1000000",
            "--set",
            "rrt_star.neighbor_radius=1e6",
        ])
        .current_dir(d)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let has_tmp = || {
        std::fs::read_dir(d)
            .unwrap()
            .any(|e| e.unwrap().file_name().to_string_lossy().contains(".tmp-"))
    };
    while !has_tmp() && t0.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(has_tmp(), "no temporary directory appeared");
    // Well inside the planning (the tree alone takes minutes).
    std::thread::sleep(Duration::from_millis(500));
    let pid = child.id().to_string();
    assert!(
        Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success()
    );
    let t1 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t1.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("the first SIGINT did not stop the planning");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted (SIGINT)"), "{err}");
    let left: Vec<_> = std::fs::read_dir(d).unwrap().collect();
    assert!(left.is_empty(), "left {left:?}");
}

/// `run s.toml --no-plots ARGS` on `simple` with `from` replaced by `to`
/// fails with one line containing every needle.
fn simple_fails(from: &str, to: &str, args: &[&str], needles: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let text = simple_toml();
    assert!(text.contains(from), "{from}");
    std::fs::write(tmp.path().join("s.toml"), text.replacen(from, to, 1)).unwrap();
    let mut all = vec!["run", "s.toml", "--no-plots"];
    all.extend_from_slice(args);
    fails_in(tmp.path(), &all, needles);
}

#[test]
fn people_stay_in_range_and_are_bounded_in_number() {
    let person = "[[obstacles]]\nvertices = [[999990.0, 0.0], [999990.5, 0.0], [999990.5, 0.5]]\nvelocity = [1.0, 0.0]\n\n[[obstacles]]";
    simple_fails(
        "[[obstacles]]",
        person,
        &[],
        &[
            "s.toml",
            "obstacles[0].velocity",
            "coordinate limit",
            "t = 9",
        ],
    );
    // Legal when the run ends before the person gets there.
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("s.toml"),
        simple_toml().replacen("[[obstacles]]", person, 1).replacen(
            "time_limit = 120.0",
            "time_limit = 5.0",
            1,
        ),
    )
    .unwrap();
    let o = sim(&["run", "s.toml", "--no-plots"], tmp.path());
    assert!(o.status.success(), "{}", text(&o.stderr));
    // 1001 people.
    let crowd: String = (0..1001)
        .map(|k| {
            let y = 100.0 + k as f64;
            format!(
                "[[obstacles]]\nvertices = [[50.0, {y}], [50.5, {y}], [50.5, {}]]\nvelocity = [0.0, 0.1]\n\n",
                y + 0.5
            )
        })
        .collect();
    simple_fails(
        "[[obstacles]]",
        &format!("{crowd}[[obstacles]]"),
        &[],
        &["s.toml", "1001 moving obstacles", "1000"],
    );
}

#[test]
fn map_settings_that_break_the_safety_promise_are_refused() {
    let lidar = ["--set", "perception=\"lidar\""];
    for (set, needles) in [
        (
            "lidar.map.padding=0",
            &["lidar.map.padding", "frontier"][..],
        ),
        ("lidar.map.resolution=1.0", &["lidar.map.resolution"][..]),
        (
            "lidar.map.unknown_radius=0",
            &["lidar.map.unknown_radius"][..],
        ),
    ] {
        let mut args = lidar.to_vec();
        args.extend(["--set", set, "--set", "lidar.map.grow=false"]);
        simple_fails("", "", &args, needles);
    }
}

#[test]
fn output_names_of_any_bytes_and_up_to_255_bytes_are_written() {
    use std::os::unix::ffi::OsStrExt;
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let long = "n".repeat(255);
    let o = sim(&["run", "simple", "--no-plots", "--out", &long], d);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(d.join(&long).join("summary.json").is_file());
    // A name that is not UTF-8.
    let name = std::ffi::OsStr::from_bytes(b"out-\xff");
    let o = Command::new(env!("CARGO_BIN_EXE_ldcbf-sim"))
        .args(["run", "simple", "--no-plots", "--out"])
        .arg(name)
        .current_dir(d)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(d.join(name).join("summary.json").is_file());
    let names: Vec<_> = std::fs::read_dir(d).unwrap().collect();
    assert_eq!(names.len(), 2, "only the two outputs: {names:?}");
}
