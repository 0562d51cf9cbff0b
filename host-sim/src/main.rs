//! `ldcbf-sim`: run the LDCBF footstep MPC in closed loop on a scenario.
//!
//! ```text
//! ldcbf-sim run <scenario> [--out DIR] [--seed S] [--set key=value ...]
//!               [--solver own|clarabel] [--mpc-rate 20|step] [--no-plots] [--no-gif] [--no-mcap]
//!               [--repeat K]
//! ldcbf-sim list
//! ldcbf-sim batch --family random --seeds 0..200 [--planner none|rrt_star]
//!                 [--perception known|lidar] [--jobs J] [--shard I/N] [--out DIR] [--set k=v ...]
//! ldcbf-sim merge DIR... --out DIR [--allow-partial]   (batch or robustness shards)
//! ldcbf-sim table DIR...
//! ldcbf-sim deadline [CASES...] [--random N] [--deadline-us D] [--clock-mhz F]
//!                    [--set k=v ...] [--jobs J] [--repeat K] [--instructions FILE]
//! ldcbf-sim robustness [CASES...] [--random N] [--delta D,D,...] [--set k=v ...]
//!                      [--jobs J] [--shard I/N] [--out DIR]
//! ```
//!
//! Exit status: 0 success; 1 error, with one `error: ...` line on stderr and no
//! partial output (docs/cli-errors.md); 2 bad arguments (clap); 141 stdout
//! closed by the reader (no message).
//!
//! The arguments, the subcommands and the output are the library's `cli` room
//! (`src/cli/`).

use std::process::ExitCode;

fn main() -> ExitCode {
    ldcbf_sim::cli::main()
}
