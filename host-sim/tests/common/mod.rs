//! Helpers shared by the CLI tests: run the `ldcbf-sim` binary and check a
//! failing command.
#![allow(dead_code)] // each test file uses its own subset

use std::path::Path;
use std::process::{Command, Output};

/// Runs `ldcbf-sim` with `args` in `cwd`.
pub fn sim(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ldcbf-sim"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("binary runs")
}

/// Output bytes as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Runs a command that must fail: non-zero exit, nothing on stdout, exactly one
/// `error:` line on stderr containing `needle`, and an empty working directory
/// afterwards.
pub fn fails(args: &[&str], needle: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let o = sim(args, tmp.path());
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(out.is_empty(), "{args:?} printed {out}");
    assert!(err.contains(needle), "{args:?}: {err}");
    let errors = err.lines().filter(|l| l.starts_with("error")).count();
    assert_eq!(errors, 1, "{args:?}: {err}");
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        0,
        "{args:?} wrote something"
    );
}
