//! Bad input on every path of `ldcbf-sim` that reads a file or a directory, or
//! writes one: a missing, empty, truncated or wrong-typed input, and an
//! unusable output location. Each case runs the binary in a fresh directory
//! holding its fixture and checks (see `common::fails_in`) the exit status 1,
//! the single `error:` line naming the file (and the field, key or line), and
//! that the directory is exactly as before: nothing created, nothing
//! half-written, no input changed. The contract is listed in docs/cli-errors.md.

mod common;
use common::{fails_in, npy, npy_f64, sim, small_qp, text, zip};

use std::path::Path;
use std::sync::OnceLock;

/// The shipped `simple` scenario, as text.
fn simple_toml() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/simple.toml"))
        .unwrap()
}

/// The first bytes of a PNG file (a binary, non-UTF-8 input).
const PNG: &[u8] = b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR\x00\x00\x00\x01\xff\xfe";

/// Fixture files: relative path (a directory when it ends in `/`) and bytes.
type Files = Vec<(String, Vec<u8>)>;

/// One case: the fixture (files, by relative path; a path ending in `/` is a
/// directory), the arguments and the texts the error line must contain.
struct Case {
    files: Files,
    args: Vec<String>,
    needles: Vec<String>,
}

fn case(files: &[(&str, &[u8])], args: &str, needles: &[&str]) -> Case {
    Case {
        files: files
            .iter()
            .map(|(p, b)| (p.to_string(), b.to_vec()))
            .collect(),
        args: args.split_whitespace().map(String::from).collect(),
        needles: needles.iter().map(|s| s.to_string()).collect(),
    }
}

/// Sets up each case in its own temporary directory and checks it.
fn check(cases: Vec<Case>) {
    for c in cases {
        let tmp = tempfile::tempdir().unwrap();
        for (p, bytes) in &c.files {
            let path = tmp.path().join(p);
            if p.ends_with('/') {
                std::fs::create_dir_all(&path).unwrap();
            } else {
                std::fs::create_dir_all(path.parent().unwrap()).unwrap();
                std::fs::write(&path, bytes).unwrap();
            }
        }
        let args: Vec<&str> = c.args.iter().map(String::as_str).collect();
        let needles: Vec<&str> = c.needles.iter().map(String::as_str).collect();
        fails_in(tmp.path(), &args, &needles);
    }
}

// ------------------------------------------------------------ scenario files

/// The bad scenario files (name, bytes, texts of the error), read by `run`,
/// `batch --family` and `deadline` alike.
fn bad_scenarios() -> Vec<(&'static str, Vec<u8>, Vec<&'static str>)> {
    let simple = simple_toml();
    let cut = simple.find("radius = 0.7").unwrap() + 6;
    // The error names the line of the cut obstacle.
    let cut_line: &'static str =
        Box::leak(format!("trunc.toml:{}:", simple[..cut].lines().count()).into_boxed_str());
    vec![
        (
            "missing.toml",
            Vec::new(),
            vec!["missing.toml: no such file"],
        ),
        ("empty.toml", Vec::new(), vec!["empty.toml:1:", "`name`"]),
        (
            "trunc.toml",
            simple.as_bytes()[..cut].to_vec(),
            vec![cut_line, "obstacles"],
        ),
        (
            "json.toml",
            br#"{"name": "simple", "goal": [5, 5]}"#.to_vec(),
            vec!["json.toml:1:"],
        ),
        (
            "png.toml",
            PNG.to_vec(),
            vec!["png.toml: cannot read", "UTF-8"],
        ),
        ("dir.toml/", Vec::new(), vec!["dir.toml", "is a directory"]),
        (
            "type.toml",
            simple
                .replace("time_limit = 120.0", "time_limit = \"soon\"")
                .into_bytes(),
            vec!["type.toml:8:", "time_limit"],
        ),
        // A key given twice: the error names that key, not the one before it
        // (it named `time_limit` for a second `goal` on the line after it).
        (
            "dup.toml",
            simple
                .replace(
                    "time_limit = 120.0",
                    "time_limit = 120.0\ngoal = [1.0, 1.0]",
                )
                .into_bytes(),
            vec!["dup.toml:9:", "field `goal`", "duplicate key"],
        ),
        // Impossible scenarios: no room for the robot's body at the start or goal.
        (
            "start_inside.toml",
            impossible("{ x = 1.1, y = 0.0 }", "[5.0, 0.0]", ""),
            vec!["start_inside.toml:2:", "`start`", "is inside obstacles[0]"],
        ),
        (
            "start_near.toml",
            impossible("{ x = 0.9, y = 0.0 }", "[5.0, 0.0]", ""),
            vec![
                "start_near.toml:2:",
                "`start`",
                "obstacles[0]",
                "body radius 0.25 m",
            ],
        ),
        (
            "goal_inside.toml",
            impossible("{ x = -2.0, y = 0.0 }", "[1.1, 0.5]", ""),
            vec!["goal_inside.toml:3:", "`goal`", "is inside obstacles[0]"],
        ),
        (
            "goal_near.toml",
            impossible(
                "{ x = -2.0, y = 0.0 }",
                "[0.6, 0.0]",
                "[robot]\nbody_radius = 0.45\n",
            ),
            vec![
                "goal_near.toml:3:",
                "`goal`",
                "obstacles[0]",
                "body radius 0.45 m",
            ],
        ),
    ]
}

/// A scenario with one wall (x in [1.0, 1.2], y in [-1, 1]), `start` and `goal`
/// as TOML values, and extra tables.
fn impossible(start: &str, goal: &str, extra: &str) -> Vec<u8> {
    format!(
        "name = \"x\"\nstart = {start}\ngoal = {goal}\n{extra}\
         [[obstacles]]\nvertices = [[1.0, -1.0], [1.2, -1.0], [1.2, 1.0], [1.0, 1.0]]\n"
    )
    .into_bytes()
}

/// The fixture of a scenario case (a missing file has none).
fn scenario_fixture(name: &str, bytes: &[u8]) -> Files {
    if name == "missing.toml" {
        Vec::new()
    } else {
        vec![(name.to_string(), bytes.to_vec())]
    }
}

#[test]
fn run_batch_and_deadline_reject_bad_scenario_files() {
    let mut cases = Vec::new();
    for (name, bytes, needles) in bad_scenarios() {
        let file = name.trim_end_matches('/');
        for args in [
            format!("run {file} --out res --no-plots"),
            format!("run {file} --export-qps qps"),
            format!("batch --seeds 0..2 --family {file} --quiet"),
            format!("deadline {file}"),
            format!("deadline simple {file}@3"),
        ] {
            let mut c = case(&[], &args, &needles);
            c.files = scenario_fixture(name, &bytes);
            cases.push(c);
        }
    }
    // A name that is no shipped scenario.
    cases.push(case(&[], "run nope", &["no scenario named \"nope\""]));
    cases.push(case(
        &[],
        "batch --seeds 0 --family nope",
        &["no scenario named \"nope\""],
    ));
    check(cases);
}

// ------------------------------------------------------------ output locations

#[test]
fn run_and_batch_refuse_unusable_output_locations() {
    let file: &[(&str, &[u8])] = &[("taken", b"not a directory")];
    let foreign: &[(&str, &[u8])] = &[("mine/notes.txt", b"keep me")];
    let mut cases = Vec::new();
    for cmd in [
        "run simple --no-plots",
        "batch --seeds 0 --quiet",
        "merge b --allow-partial",
        "robustness simple --random 0 --delta 0 --quiet",
    ] {
        // `merge` needs a valid batch directory: added below.
        for (fixture, out, needles) in [
            (
                file,
                "taken",
                vec!["--out taken", "is a file, not a directory"],
            ),
            (
                file,
                "taken/sub",
                vec!["--out taken/sub", "taken is a file, not a directory"],
            ),
            (
                foreign,
                "mine",
                vec!["--out mine", "not a previous ldcbf-sim output"],
            ),
            (file, ".", vec!["--out .", "no usable last component"]),
        ] {
            cases.push(case(fixture, &format!("{cmd} --out {out}"), &needles));
        }
    }
    // `run --export-qps`: the same, and never the output directory itself or
    // inside it (checked before the simulation; nothing created).
    for (fixture, args, needles) in [
        (
            file,
            "run simple --no-plots --out new/res --export-qps taken",
            vec!["--export-qps taken", "is a file, not a directory"],
        ),
        (
            file,
            "run simple --no-plots --out new/res --export-qps taken/q",
            vec!["--export-qps taken/q", "taken is a file"],
        ),
        (
            foreign,
            "run simple --no-plots --out new/res --export-qps mine",
            vec!["--export-qps mine", "not a previous ldcbf-sim output"],
        ),
        (
            file,
            "run simple --no-plots --out o --export-qps o",
            vec!["--export-qps o", "apart from the output directory o"],
        ),
        (
            file,
            "run simple --no-plots --out o --export-qps ./o/../o/qps",
            vec!["--export-qps ./o/../o/qps", "apart from"],
        ),
        (
            file,
            "run simple --no-plots --out o/res --export-qps o",
            vec!["--export-qps o", "apart from"],
        ),
    ] {
        cases.push(case(fixture, args, &needles));
    }
    for c in cases.iter_mut() {
        if c.args[0] == "merge" {
            c.files.extend(batch_files("b"));
        }
    }
    check(cases);
}

// ------------------------------------------------------------ batch directories

/// The files of a valid batch directory (seed 0 of `random`, shard 1/2), made
/// once with `ldcbf-sim batch`.
fn batch_dir() -> &'static [(String, Vec<u8>)] {
    static DIR: OnceLock<Files> = OnceLock::new();
    DIR.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let o = sim(
            &[
                "batch", "--seeds", "0..2", "--shard", "1/2", "--out", "b", "--quiet", "--jobs",
                "1",
            ],
            tmp.path(),
        );
        assert!(o.status.success(), "{}", text(&o.stderr));
        ["summary.json", "runs.csv", "summary.md"]
            .iter()
            .map(|f| {
                (
                    f.to_string(),
                    std::fs::read(tmp.path().join("b").join(f)).unwrap(),
                )
            })
            .collect()
    })
}

/// The valid batch directory as fixture files under `dir/`.
fn batch_files(dir: &str) -> Files {
    batch_dir()
        .iter()
        .map(|(f, b)| (format!("{dir}/{f}"), b.clone()))
        .collect()
}

/// The valid batch directory `b/` with `file` replaced by `bytes` (`None`:
/// removed).
fn batch_with(file: &str, bytes: Option<&[u8]>) -> Files {
    let mut files: Files = batch_files("b")
        .into_iter()
        .filter(|(p, _)| p != &format!("b/{file}"))
        .collect();
    if let Some(b) = bytes {
        files.push((format!("b/{file}"), b.to_vec()));
    }
    files
}

#[test]
fn merge_and_table_reject_bad_batch_directories() {
    let get = |f: &str| batch_dir().iter().find(|(p, _)| p == f).unwrap().1.clone();
    let (summary, runs) = (get("summary.json"), get("runs.csv"));
    let summary_text = String::from_utf8(summary.clone()).unwrap();
    let runs_text = String::from_utf8(runs.clone()).unwrap();
    let header_only = runs_text.lines().next().unwrap().to_string() + "\n";
    let row = runs_text.lines().nth(1).unwrap();
    let bad_row = runs_text.replacen(
        row,
        &row.replacen(",goal_reached,1,", ",goal_reached,yes,", 1),
        1,
    );
    assert_ne!(bad_row, runs_text, "the fixture's run reached the goal");
    let fixtures: Vec<(Files, Vec<&str>)> = vec![
        (Vec::new(), vec!["b: no such batch directory"]),
        (
            vec![("b".into(), b"a file".to_vec())],
            vec!["b: is a file, not a batch directory"],
        ),
        (
            vec![("b/".into(), Vec::new())],
            vec!["b: not a batch directory (no summary.json"],
        ),
        (
            batch_with("summary.json", None),
            vec!["b: not a batch directory (no summary.json"],
        ),
        (
            batch_with("runs.csv", None),
            vec!["b: not a batch directory (no runs.csv"],
        ),
        (
            batch_with("summary.json", Some(b"")),
            vec!["b/summary.json: empty file"],
        ),
        (
            batch_with("summary.json", Some(&summary[..summary.len() / 2])),
            vec!["b/summary.json: not a batch summary", "EOF while parsing"],
        ),
        (
            batch_with("summary.json", Some(PNG)),
            vec!["b/summary.json: not a text file"],
        ),
        (
            batch_with("summary.json", Some(b"name = \"simple\"\n")),
            vec!["b/summary.json: not a batch summary"],
        ),
        // A `run` summary (another schema) instead of a batch summary.
        (
            batch_with(
                "summary.json",
                Some(br#"{"scenario": "simple", "outcome": "goal_reached", "steps": 3}"#),
            ),
            vec![
                "b/summary.json: not a batch summary",
                "missing field `meta`",
            ],
        ),
        (
            batch_with(
                "summary.json",
                Some(
                    summary_text
                        .replacen("\"runs\": 1", "\"runs\": \"one\"", 1)
                        .as_bytes(),
                ),
            ),
            vec![
                "b/summary.json: not a batch summary",
                "invalid type: string \"one\"",
            ],
        ),
        (
            batch_with(
                "summary.json",
                Some(
                    summary_text
                        .replacen("\"ldcbf-sim batch\"", "\"something else\"", 1)
                        .as_bytes(),
                ),
            ),
            vec!["b/summary.json: field `meta.kind`"],
        ),
        (
            vec![
                ("b/summary.json/".into(), Vec::new()),
                ("b/runs.csv".into(), runs.clone()),
            ],
            vec!["b/summary.json: cannot read"],
        ),
        (
            batch_with("runs.csv", Some(b"")),
            vec!["b/runs.csv: empty file"],
        ),
        (
            batch_with("runs.csv", Some(&runs[..runs.len() - 3])),
            vec!["b/runs.csv:2: the last line ends without a newline"],
        ),
        (
            batch_with("runs.csv", Some(&runs[..40])),
            vec!["b/runs.csv:1: unexpected header"],
        ),
        (
            batch_with("runs.csv", Some(header_only.as_bytes())),
            vec!["b/runs.csv: 0 rows but summary.json says 1 runs"],
        ),
        (
            batch_with("runs.csv", Some(bad_row.as_bytes())),
            vec!["b/runs.csv:2: bad success \"yes\""],
        ),
        (
            batch_with("runs.csv", Some(PNG)),
            vec!["b/runs.csv: not a text file"],
        ),
        (
            batch_with("runs.csv", Some(&summary)),
            vec!["b/runs.csv:1: unexpected header"],
        ),
    ];
    let mut cases = Vec::new();
    for (files, needles) in fixtures {
        for args in [
            "table b",
            "merge b --out m --allow-partial",
            "merge good b --out m",
        ] {
            let mut c = case(&[], args, &needles);
            c.files = files.clone();
            if args.contains("good") {
                c.files.extend(batch_files("good"));
            }
            cases.push(c);
        }
    }
    check(cases);
}

// ------------------------------------------------------------ npz files

/// A small valid QP (n = 6, m = 1) and its npz bytes.
fn good_npz() -> Vec<u8> {
    let tmp = tempfile::tempdir().unwrap();
    let f = tmp.path().join("a.npz");
    small_qp().write_npz(&f).unwrap();
    std::fs::read(f).unwrap()
}

/// An npz of `P, q, G, h` with one member replaced (`None`: left out).
fn npz_with(key: &str, member: Option<Vec<u8>>) -> Vec<u8> {
    let mut eye = vec![0.0; 36];
    for i in 0..6 {
        eye[i * 6 + i] = 2.0;
    }
    let name = format!("{key}.npy");
    let mut members: Vec<(&str, Vec<u8>)> = vec![
        ("P.npy", npy_f64(&[6, 6], &eye)),
        ("q.npy", npy_f64(&[6], &[-2.0; 6])),
        ("G.npy", npy_f64(&[1, 6], &[1.0, 1.0, 0.0, 0.0, 0.0, 0.0])),
        ("h.npy", npy_f64(&[1], &[1.0])),
    ];
    members.retain(|(n, _)| *n != name);
    if let Some(m) = member {
        members.push((&name, m));
    }
    zip(&members)
}

#[test]
fn qp_solve_rejects_bad_npz_files() {
    let good = good_npz();
    // The hand-made archive is a valid QP: it solves.
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("hand.npz"), npz_with("A", None)).unwrap();
    std::fs::write(tmp.path().join("good.npz"), &good).unwrap();
    let o = sim(&["qp", "solve", "hand.npz", "good.npz"], tmp.path());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert_eq!(out.lines().count(), 3, "{out}");
    assert!(
        out.lines().skip(1).all(|l| l.contains(",6,1,solved,1,")),
        "{out}"
    );

    let mut corrupt = npz_with("A", None);
    let at = corrupt
        .windows(8)
        .position(|w| w == 2.0f64.to_le_bytes())
        .unwrap();
    corrupt[at + 7] ^= 0x01; // a value of P changed: the zip CRC no longer matches
    let mut cut_member = npy_f64(&[6, 6], &[1.0; 36]);
    cut_member.truncate(cut_member.len() - 8);
    let bad: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        ("missing.npz", Vec::new(), vec!["missing.npz: no such file"]),
        ("empty.npz", Vec::new(), vec!["empty.npz: not an npz file"]),
        (
            "trunc.npz",
            good[..good.len() / 2].to_vec(),
            vec!["trunc.npz: not an npz file"],
        ),
        (
            "toml.npz",
            simple_toml().into_bytes(),
            vec!["toml.npz: not an npz file"],
        ),
        ("png.npz", PNG.to_vec(), vec!["png.npz: not an npz file"]),
        ("dir.npz/", Vec::new(), vec!["dir.npz: is a directory"]),
        (
            "plain.npz",
            npy_f64(&[6, 6], &[0.0; 36]),
            vec!["plain.npz: not an npz file"],
        ),
        (
            "noP.npz",
            npz_with("P", None),
            vec!["noP.npz: key `P`: is missing"],
        ),
        (
            "noh.npz",
            npz_with("h", None),
            vec!["noh.npz: key `h`: is missing"],
        ),
        (
            "f32.npz",
            npz_with("P", Some(npy("<f4", false, "(6, 6)", &[0; 144]))),
            vec!["f32.npz: key `P`: dtype '<f4' is not float64"],
        ),
        (
            "int.npz",
            npz_with("q", Some(npy("<i8", false, "(6,)", &[0; 48]))),
            vec!["int.npz: key `q`: dtype '<i8' is not float64"],
        ),
        (
            "pickle.npz",
            npz_with("G", Some(npy("|O", false, "()", b"\x80\x02N."))),
            vec!["pickle.npz: key `G`: is a pickled None, but `h` is given (shape [1])"],
        ),
        (
            "noneP.npz",
            npz_with("P", Some(npy("|O", false, "()", b"\x80\x02N."))),
            vec!["noneP.npz: key `P`: dtype '|O' is not float64"],
        ),
        (
            "object.npz",
            npz_with("G", Some(npy("|O", false, "(1, 6)", b"\x80\x02N."))),
            vec!["object.npz: key `G`: dtype '|O' is not float64"],
        ),
        (
            "nanlb.npz",
            npz_with(
                "lb",
                Some(npy_f64(&[6], &[0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0])),
            ),
            vec!["nanlb.npz: key `lb`: entry [1] is NaN"],
        ),
        (
            "notnpy.npz",
            npz_with("h", Some(b"1.0 2.0".to_vec())),
            vec!["notnpy.npz: key `h`: not an .npy array"],
        ),
        (
            "flatP.npz",
            npz_with("P", Some(npy_f64(&[36], &[1.0; 36]))),
            vec!["flatP.npz: key `P` has shape [36], expected [n, n]"],
        ),
        (
            "q2d.npz",
            npz_with("q", Some(npy_f64(&[1, 6], &[0.0; 6]))),
            vec!["q2d.npz: key `q` has shape [1, 6], expected [6]"],
        ),
        (
            "gcols.npz",
            npz_with("G", Some(npy_f64(&[1, 5], &[0.0; 5]))),
            vec!["gcols.npz: key `G` has shape [1, 5], expected [m, 6]"],
        ),
        (
            "hlen.npz",
            npz_with("h", Some(npy_f64(&[2], &[0.0; 2]))),
            vec!["hlen.npz: key `h` has shape [2], expected [1] (the rows of `G`)"],
        ),
        (
            "cut.npz",
            npz_with("P", Some(cut_member)),
            vec!["cut.npz: key `P`: shape [6, 6] does not match the 280 bytes"],
        ),
        (
            "huge.npz",
            npz_with(
                "P",
                Some(npy(
                    "<f8",
                    false,
                    "(1099511627776, 1099511627776)",
                    &[0; 64],
                )),
            ),
            vec!["huge.npz: key `P`: shape [1099511627776, 1099511627776] does not match"],
        ),
        (
            "corrupt.npz",
            corrupt,
            vec!["corrupt.npz: key `P`: truncated or corrupted"],
        ),
    ];
    let mut cases = Vec::new();
    for (name, bytes, needles) in bad {
        let file = name.trim_end_matches('/');
        let mut fixture = vec![("good.npz".to_string(), good.clone())];
        if name != "missing.npz" {
            fixture.push((name.to_string(), bytes));
        }
        // Alone, and after a good file: no partial CSV either way.
        for args in [
            format!("qp solve {file}"),
            format!("qp solve good.npz {file} --repeat 2"),
        ] {
            let mut c = case(&[], &args, &needles);
            c.files = fixture.clone();
            cases.push(c);
        }
    }
    check(cases);
}

// ------------------------------------------------------------ instruction CSV

#[test]
fn deadline_rejects_bad_instruction_files() {
    const GOOD: &str =
        "cycle,status,iterations,instructions\n0,optimal,12,45000\n1,optimal,14,47000\n";
    let bad: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        ("missing.csv", Vec::new(), vec!["missing.csv: cannot read"]),
        ("empty.csv", Vec::new(), vec!["empty.csv: empty file"]),
        (
            "trunc.csv",
            GOOD.as_bytes()[..GOOD.len() - 3].to_vec(),
            vec!["trunc.csv:3: the last line ends without a newline"],
        ),
        (
            "cut.csv",
            GOOD.as_bytes()[..GOOD.len() - 12].to_vec(),
            vec!["cut.csv:3:"],
        ),
        (
            "json.csv",
            br#"{"cycle": 0, "instructions": 45000}"#.to_vec(),
            vec!["json.csv:"],
        ),
        ("png.csv", PNG.to_vec(), vec!["png.csv: not a text file"]),
        ("dir.csv/", Vec::new(), vec!["dir.csv: is a directory"]),
        (
            "header.csv",
            b"cycle,status,iterations,instructions\n".to_vec(),
            vec!["header.csv: no cycles"],
        ),
        (
            "field.csv",
            GOOD.replace("47000", "many").into_bytes(),
            vec!["field.csv:3: bad instructions"],
        ),
        (
            "runs.csv",
            batch_dir()
                .iter()
                .find(|(p, _)| p == "runs.csv")
                .unwrap()
                .1
                .clone(),
            vec!["runs.csv:1: expected the header"],
        ),
    ];
    let mut cases = Vec::new();
    for (name, bytes, needles) in bad {
        let file = name.trim_end_matches('/');
        let mut c = case(
            &[],
            &format!("deadline simple --instructions {file}"),
            &needles,
        );
        if name != "missing.csv" {
            c.files.push((name.to_string(), bytes));
        }
        cases.push(c);
    }
    check(cases);
}

/// A good run after the bad ones: the checks do not refuse valid input, the
/// QP directory of a previous run is replaced on a re-run, and a failed run
/// leaves the previous results as they were.
#[test]
fn good_input_still_works_and_previous_outputs_survive_a_failure() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path();
    for _ in 0..2 {
        let o = sim(
            &[
                "run",
                "simple",
                "--no-plots",
                "--out",
                "o",
                "--export-qps",
                "q/qps",
            ],
            p,
        );
        assert!(o.status.success(), "{}", text(&o.stderr));
    }
    assert!(p.join("o/summary.json").is_file());
    assert!(p.join("q/qps/cycle_00000.npz").is_file());
    // A failing run into the same places changes nothing.
    std::fs::write(p.join("bad.toml"), "name = \"bad\"\n").unwrap();
    fails_in(
        p,
        &["run", "bad.toml", "--out", "o", "--export-qps", "q/qps"],
        &["bad.toml"],
    );
}
