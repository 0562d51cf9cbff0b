//! A closed stdout (`ldcbf-sim ... | head -1`) ends every subcommand quietly
//! with status 141 (128 + SIGPIPE, as `cat` or `grep` end under a shell), no
//! panic message, and the output directories complete; a closed stderr does
//! not turn an error into a panic either.

mod common;
use common::{sim, text};

use std::path::Path;
use std::process::{Command, Stdio};

/// Runs `ldcbf-sim args` in `cwd` with stdout a pipe whose read end is closed
/// before the process starts, so that its first write fails (deterministic,
/// unlike closing it while the child runs). Returns (status code, stderr).
fn with_closed_stdout(args: &[&str], cwd: &Path) -> (Option<i32>, String) {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = Command::new(env!("CARGO_BIN_EXE_ldcbf-sim"))
        .args(args)
        .current_dir(cwd)
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    (o.status.code(), text(&o.stderr))
}

#[test]
fn every_subcommand_exits_quietly_when_stdout_is_closed() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path();
    // Inputs: a batch directory and an exported QP.
    let o = sim(
        &[
            "run",
            "simple",
            "--no-plots",
            "--out",
            "r",
            "--export-qps",
            "q",
        ],
        p,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = sim(&["batch", "--seeds", "0", "--out", "b", "--quiet"], p);
    assert!(o.status.success(), "{}", text(&o.stderr));
    for args in [
        &["list"][..],
        &["table", "b"],
        &["qp", "solve", "q/cycle_00000.npz", "q/cycle_00001.npz"],
        &["merge", "b", "--out", "m"],
        &["run", "simple", "--no-plots", "--out", "r2"],
        &["batch", "--seeds", "1", "--out", "b2", "--quiet"],
        &["deadline", "simple"],
    ] {
        let (code, err) = with_closed_stdout(args, p);
        assert_eq!(code, Some(141), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?} wrote to stderr: {err}");
    }
    // The outputs were complete before anything was printed.
    for f in [
        "m/summary.json",
        "m/runs.csv",
        "r2/summary.json",
        "b2/runs.csv",
    ] {
        assert!(p.join(f).is_file(), "{f}");
    }
    // The `--help` text goes through clap, which handles a closed stdout itself.
    let (code, err) = with_closed_stdout(&["--help"], p);
    assert!(!err.contains("panicked"), "{err}");
    assert_ne!(code, Some(101), "{err}");
}

#[test]
fn an_error_with_stderr_closed_is_no_panic() {
    let tmp = tempfile::tempdir().unwrap();
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let status = Command::new(env!("CARGO_BIN_EXE_ldcbf-sim"))
        .args(["run", "missing.toml"])
        .current_dir(tmp.path())
        .stdout(Stdio::null())
        .stderr(writer)
        .status()
        .unwrap();
    assert_eq!(status.code(), Some(1));
}
