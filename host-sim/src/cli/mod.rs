//! The command line's room, the top one (it may use every other room): the
//! `ldcbf-sim` binary's arguments (`args`, clap), one function per
//! subcommand returning `anyhow::Result` (`run`, `batch`, `studies`, `qp`),
//! what it prints and its exit status (`output`), and the `run` pipeline
//! ([`app`]). `src/main.rs` only calls [`main`].

pub mod app;
mod args;
mod batch;
mod output;
mod qp;
mod run;
mod studies;

use std::process::ExitCode;

use anyhow::{Result, anyhow};
use clap::Parser as _;

use args::{Cli, Command, QpCommand};

/// The `ldcbf-sim` binary: parses the command line (clap exits with status 2
/// on bad arguments), installs the SIGINT/SIGTERM handlers and runs the
/// subcommand. Exit status: 0 success; 1 error, with one `error: ...` line on
/// stderr (docs/cli-errors.md); 128 + signal when stopped; 141 when stdout is
/// closed by the reader.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match start().and_then(|()| dispatch(cli.command)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => output::fail(e),
    }
}

/// Installs the signal handlers that stop a run cleanly ([`crate::sim::cancel`]).
fn start() -> Result<()> {
    crate::sim::cancel::install_signal_handlers()
        .map_err(|e| anyhow!("cannot install the SIGINT/SIGTERM handlers: {e}"))
}

/// Runs one subcommand.
fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Run(a) => run::run(a),
        Command::List => run::list(),
        Command::Batch(a) => batch::batch(a),
        Command::Merge(a) => batch::merge(a),
        Command::Table(a) => batch::table(a),
        Command::Deadline(a) => studies::deadline(a),
        Command::Robustness(a) => studies::robustness(a),
        Command::Crowdnav(a) => studies::crowdnav(a),
        Command::Qp {
            command: QpCommand::Solve(a),
        } => qp::solve(a),
    }
}
