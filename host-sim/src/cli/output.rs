//! What the binary prints: stdout through [`emit`] (a closed pipe ends the
//! process quietly), and an error as one `error: ...` line on stderr
//! ([`fail`]) with the exit status of docs/cli-errors.md.

use std::process::ExitCode;

/// Exit status when stdout is closed early (`ldcbf-sim list | head -1`): the
/// shell's status of a process killed by SIGPIPE (128 + 13), without a message,
/// as `cat`, `grep` and friends end; the output directories are complete by the
/// time anything is printed.
const EXIT_BROKEN_PIPE: u8 = 141;

/// Writes `text` to stdout. A closed stdout (broken pipe) ends the process
/// quietly with [`EXIT_BROKEN_PIPE`]; any other write error ends it with one
/// error line and status 1. (`print!` would panic instead.)
pub(crate) fn emit(text: &str) {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(i32::from(EXIT_BROKEN_PIPE));
        }
        drop(out);
        let _ = fail(anyhow::anyhow!("cannot write to stdout: {e}"));
        std::process::exit(1);
    }
}

/// `print!` through [`emit`].
macro_rules! out {
    ($($t:tt)*) => { $crate::cli::output::emit(&format!($($t)*)) };
}
pub(crate) use out;

/// `println!` through [`emit`].
macro_rules! outln {
    ($($t:tt)*) => { $crate::cli::output::emit(&format!("{}\n", format_args!($($t)*))) };
}
pub(crate) use outln;

/// Prints the error as one line `error: ...` on stderr (the causes joined with
/// `: `; line breaks inside a message become `; `) and returns status 1. A
/// closed stderr is ignored.
pub(crate) fn fail(err: anyhow::Error) -> ExitCode {
    use std::io::Write as _;
    // Stopped by SIGINT or SIGTERM: the temporary outputs are gone; the status
    // is the shell's 128 + signal.
    if let Err(c) = crate::sim::cancel::check() {
        let _ = writeln!(
            std::io::stderr().lock(),
            "error: {c}: stopped, nothing written"
        );
        return ExitCode::from(128 + c.signal.map_or(2, |s| s as u8));
    }
    let msg = format!("{err:#}");
    let one_line: Vec<&str> = msg
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    let _ = writeln!(std::io::stderr().lock(), "error: {}", one_line.join("; "));
    ExitCode::FAILURE
}
