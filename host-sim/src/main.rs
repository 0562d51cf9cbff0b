//! `ldcbf-sim`: run the LDCBF footstep MPC in closed loop on a scenario.
//!
//! ```text
//! ldcbf-sim run <scenario> [--out DIR] [--seed S] [--set key=value ...]
//!               [--solver own|clarabel] [--mpc-rate 20|step] [--no-plots] [--no-gif]
//! ldcbf-sim list
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use ldcbf_sim::sim::{MpcRate, Solver};
use ldcbf_sim::{RunRequest, execute_run};

#[derive(Parser)]
#[command(
    name = "ldcbf-sim",
    version,
    about = "Closed-loop simulator of the LDCBF footstep MPC"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scenario and write logs and figures.
    Run {
        /// Scenario name (scenarios/<name>.toml) or path to a .toml file.
        scenario: String,
        /// Output directory [default: out/<name>, out/<name>-seed<S> for random ones].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Seed of the scenario's random generator (e.g. `run random --seed 7`).
        #[arg(long)]
        seed: Option<u64>,
        /// Override a scenario field: `key=value` with a TOML value, e.g.
        /// `delta=0.3`, `controller.gamma=0.5`, `time_limit=200`, `goal=[5,5]`.
        #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_set)]
        sets: Vec<(String, String)>,
        /// QP solver inside the controller.
        #[arg(long, value_enum, default_value = "own")]
        solver: Solver,
        /// Controller rate: a rate in Hz (20 = the paper's), or `step` (once per step).
        #[arg(long, default_value = "20")]
        mpc_rate: MpcRate,
        /// Do not render the figures (logs and summary only).
        #[arg(long)]
        no_plots: bool,
        /// Do not render the animated GIF.
        #[arg(long)]
        no_gif: bool,
        /// Write every n-th 1 kHz sample to trajectory.csv (1 = all).
        #[arg(long, default_value_t = 10)]
        trajectory_every: usize,
    },
    /// List the scenarios shipped in scenarios/.
    List,
}

fn parse_set(s: &str) -> Result<(String, String), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected KEY=VALUE, got {s:?}"))?;
    let k = k.trim();
    if k.is_empty() {
        return Err(format!("empty key in {s:?}"));
    }
    Ok((k.to_string(), v.trim().to_string()))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::List => {
            let dir = ldcbf_sim::scenario::scenario_dir();
            println!("scenarios in {}:", dir.display());
            for (name, desc, _) in ldcbf_sim::scenario::list() {
                println!("  {name:<10} {desc}");
            }
            ExitCode::SUCCESS
        }
        Command::Run {
            scenario,
            out,
            seed,
            sets,
            solver,
            mpc_rate,
            no_plots,
            no_gif,
            trajectory_every,
        } => {
            let req = RunRequest {
                out,
                seed,
                sets,
                solver,
                mpc_rate,
                plots: !no_plots,
                gif: !no_gif,
                trajectory_every,
                ..RunRequest::new(&scenario)
            };
            match execute_run(&req) {
                Ok(rep) => {
                    print!("{}", ldcbf_sim::report::human_summary(&rep.summary));
                    println!("wrote {}/: {}", rep.out_dir.display(), rep.files.join(" "));
                    ExitCode::SUCCESS
                }
                Err(err) => {
                    eprintln!("error: {err:#}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}
