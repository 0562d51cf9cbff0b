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

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use ldcbf_sim::plan::Planner;
use ldcbf_sim::sense::Perception;
use ldcbf_sim::sim::{MpcRate, Solver};
use ldcbf_sim::studies::batch::{BatchRequest, SeedRange, Shard};
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
        #[command(flatten)]
        closed_loop: LoopArgs,
        /// Do not render the figures (logs and summary only).
        #[arg(long)]
        no_plots: bool,
        /// Do not render the animated GIF.
        #[arg(long)]
        no_gif: bool,
        /// Do not write run.mcap (the run for Foxglove, docs/foxglove.md).
        #[arg(long)]
        no_mcap: bool,
        /// Write every n-th 1 kHz sample to trajectory.csv (1 = all).
        #[arg(long, default_value_t = 10)]
        trajectory_every: usize,
        /// Also write every cycle's QP as DIR/cycle_NNNNN.npz (P, q, G, h), the
        /// layout `qp solve` reads.
        #[arg(long, value_name = "DIR")]
        export_qps: Option<PathBuf>,
        /// Timings of each controller call: `compute_ns` in cycles.csv (and the
        /// summary's compute) is the minimum of K timings on the same input and
        /// state, as in `deadline --repeat`; the run itself is the same.
        #[arg(long, default_value_t = 1, value_name = "K")]
        repeat: u32,
    },
    /// Dense QPs in the npz layout of tests/data/lipmwalk (P, q, G, h).
    Qp {
        #[command(subcommand)]
        command: QpCommand,
    },
    /// List the scenarios shipped in scenarios/.
    List,
    /// Run many seeds of a scenario family in parallel: runs.csv (one row per
    /// run), summary.json and summary.md (Markdown table).
    Batch {
        /// Scenario family: a scenario with a [generator] (name or path).
        #[arg(long, default_value = "random")]
        family: String,
        /// Seeds: `A..B` (B excluded), `A..=B`, or one seed.
        #[arg(long)]
        seeds: SeedRange,
        /// Planner (default: the scenario file's).
        #[arg(long, value_enum)]
        planner: Option<Planner>,
        /// Perception (default: the scenario file's).
        #[arg(long, value_enum)]
        perception: Option<Perception>,
        /// Worker threads [default: one per core].
        #[arg(long)]
        jobs: Option<usize>,
        /// Run only shard I of N (1-based) of the seeds, for studies split across
        /// machines; combine the shard directories with `merge`.
        #[arg(long, default_value = "1/1")]
        shard: Shard,
        /// Output directory [default: out/batch-<family>-<planner>-<perception>[-shard<I>of<N>]].
        #[arg(long)]
        out: Option<PathBuf>,
        #[command(flatten)]
        closed_loop: LoopArgs,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Merge the shard directories of one batch or robustness study into one
    /// directory.
    Merge {
        /// Shard directories written by `batch --shard I/N` or
        /// `robustness --shard I/N --out DIR`.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Merge even if some seeds (runs) of the study are missing.
        #[arg(long)]
        allow_partial: bool,
    },
    /// Print the Markdown table of one or more batch directories side by side.
    Table {
        /// Batch directories (one column each).
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
    },
    /// Deadline report: per-cycle compute time p50/p99/max (ns), solver
    /// iterations (optimal / all cycles) and the margin to the deadline, per
    /// case, as a Markdown table.
    Deadline {
        /// Cases `NAME[+rrt_star|+none][@SEED]` (a shipped scenario or a path),
        /// e.g. `maze+none`, `crowded@0` [default: the shipped cases,
        /// `ldcbf_sim::studies::deadline::SHIPPED_CASES`, and `large-map`].
        #[arg(value_name = "CASES")]
        cases: Vec<ldcbf_sim::studies::deadline::Case>,
        /// Also run seeds 0..N of the `random` family (pooled into one row).
        #[arg(long, default_value_t = 0, value_name = "N",
              value_parser = clap::value_parser!(u64).range(..=ldcbf_sim::studies::batch::MAX_SEEDS))]
        random: u64,
        /// Deadline per control cycle, µs (250 = the issue's 100,000
        /// instructions at 400 MHz).
        #[arg(long, default_value_t = ldcbf_sim::studies::deadline::DEFAULT_DEADLINE_US, value_name = "D")]
        deadline_us: f64,
        /// Target clock, MHz, to turn instruction counts into time.
        #[arg(long, default_value_t = ldcbf_sim::studies::deadline::DEFAULT_CLOCK_MHZ, value_name = "F")]
        clock_mhz: f64,
        /// Override a scenario field for every case (as for `run`).
        #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_set)]
        sets: Vec<(String, String)>,
        /// Worker threads (more than one shares the cores between runs, which
        /// shows in the wall-clock times).
        #[arg(long, default_value_t = 1)]
        jobs: usize,
        /// Timings of each control cycle: the controller call is timed K times
        /// on the same input and state (clones of the controller) and the
        /// cycle's compute time is the minimum, so a preemption does not count
        /// and the max is the hardest cycle. The closed loops (cycles, statuses,
        /// iterations) are the same for every K; the controller's share of the
        /// study's time grows K-fold. A lower bound: back-to-back timings of one
        /// input run with warm caches. With --jobs > 1 the runs still share the
        /// cores.
        #[arg(long, default_value_t = 1, value_name = "K")]
        repeat: u32,
        /// Per-cycle instruction counts of the firmware in QEMU (CSV
        /// `cycle,status,iterations,instructions`, written by
        /// tests/firmware_qemu.rs to firmware/target/instructions.csv).
        #[arg(long, value_name = "FILE")]
        instructions: Option<PathBuf>,
    },
    /// Robustness study: success, falls and true CoM clearance under pushes,
    /// CoM height mismatch, foot placement error and state estimation noise
    /// (two magnitudes each, see docs/robustness.md), for each safety margin
    /// delta, as Markdown tables. Disturbances of a single run are set with
    /// `run --set disturbance.<field>=value`; fields (body frame = x along the
    /// heading, y to its left): seed; push_time [s], push_period [s, 0 = once],
    /// push_forward, push_lateral [m/s, body frame], push_alternate [bool];
    /// plant_com_height [m]; foot_sigma [m, per world axis]; noise_position [m],
    /// noise_velocity [m/s], noise_heading [rad].
    Robustness {
        /// Cases `NAME[+rrt_star|+none][@SEED]` [default: the deadline study's
        /// shipped cases].
        #[arg(value_name = "CASES")]
        cases: Vec<ldcbf_sim::studies::deadline::Case>,
        /// Also run seeds 0..N of the `random` family.
        #[arg(long, default_value_t = 200, value_name = "N",
              value_parser = clap::value_parser!(u64).range(..=ldcbf_sim::studies::batch::MAX_SEEDS))]
        random: u64,
        /// Safety margins delta, m, comma separated (each replaces the files' own).
        #[arg(long = "delta", value_delimiter = ',', default_values_t = ldcbf_sim::studies::robustness::DEFAULT_DELTAS)]
        deltas: Vec<f64>,
        /// Override a scenario field for every run (as for `run`), e.g. `l_max=0.3`.
        #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_set)]
        sets: Vec<(String, String)>,
        /// Worker threads [default: one per core].
        #[arg(long)]
        jobs: Option<usize>,
        /// Also write DIR/runs.csv (every run), DIR/table.md and
        /// DIR/summary.json (what the study is, for `merge`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Run only shard I of N (1-based) of the runs (interleaved in the
        /// order condition, delta, case), for studies split across machines;
        /// needs --out; combine the shard directories with `merge`.
        #[arg(long, default_value = "1/1")]
        shard: Shard,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
}

#[derive(Subcommand)]
enum QpCommand {
    /// Solve each file with our solver (any size: a compiled static size when
    /// one fits, the run-time-sized instance otherwise, named in the `path`
    /// column); print CSV: status, iterations, objective and the minimum solve
    /// times over the repeats (ns, solver call only): from the raw rows, with
    /// the row norms prepared outside the timing, and by the least-distance
    /// path (prepare per G and load per q, h outside the timing; the load and
    /// the prepare are timed separately). The other paths are checked against
    /// the plain solve first (an error if they disagree).
    Solve {
        /// npz files of the qpbenchmark layout (P, q and any of G, h, A, b,
        /// lb, ub).
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Timed repeats per file (the minimum is printed).
        #[arg(long, default_value_t = 1)]
        repeat: usize,
        /// Iteration budget per solve.
        #[arg(long, default_value_t = 1000)]
        max_iter: u32,
        /// Also solve each file with Clarabel and check the agreement (primal
        /// 1e-6 scaled, objective 1e-6, feasibility verdict, Farkas
        /// certificate); columns clarabel_dx, clarabel_dobj; a disagreement is
        /// an error.
        #[arg(long)]
        check: bool,
    },
}

/// The closed-loop options shared by `run` and `batch`.
#[derive(clap::Args)]
struct LoopArgs {
    /// Override a scenario field (for every run): `key=value` with a TOML value,
    /// e.g. `delta=0.3`, `controller.gamma=0.5`, `time_limit=200`, `goal=[5,5]`,
    /// `disturbance.push_lateral=0.1` (disturbance fields: `robustness --help`).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_set)]
    sets: Vec<(String, String)>,
    /// QP solver inside the controller.
    #[arg(long, value_enum, default_value = "own")]
    solver: Solver,
    /// Controller rate: a rate in Hz (20 = the paper's), or `step` (once per step).
    #[arg(long, default_value = "20")]
    mpc_rate: MpcRate,
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

/// Exit status when stdout is closed early (`ldcbf-sim list | head -1`): the
/// shell's status of a process killed by SIGPIPE (128 + 13), without a message,
/// as `cat`, `grep` and friends end; the output directories are complete by the
/// time anything is printed.
const EXIT_BROKEN_PIPE: u8 = 141;

/// Writes `text` to stdout. A closed stdout (broken pipe) ends the process
/// quietly with [`EXIT_BROKEN_PIPE`]; any other write error ends it with one
/// error line and status 1. (`print!` would panic instead.)
fn emit(text: &str) {
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
    ($($t:tt)*) => { emit(&format!($($t)*)) };
}

/// `println!` through [`emit`].
macro_rules! outln {
    ($($t:tt)*) => { emit(&format!("{}\n", format_args!($($t)*))) };
}

/// Prints the error as one line `error: ...` on stderr (the causes joined with
/// `: `; line breaks inside a message become `; `) and returns status 1. A
/// closed stderr is ignored.
fn fail(err: anyhow::Error) -> ExitCode {
    use std::io::Write as _;
    // Stopped by SIGINT or SIGTERM: the temporary outputs are gone; the status
    // is the shell's 128 + signal.
    if let Err(c) = ldcbf_sim::sim::cancel::check() {
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

fn print_batch(rep: &ldcbf_sim::studies::batch::BatchReport) {
    let a = &rep.aggregate;
    outln!(
        "{} seeds {} shard {}: {} runs, {} successful, {} collisions, {} stuck, {} time limit, {} diverged; wall time {:.1} s",
        rep.meta.scenario,
        rep.meta.seeds,
        rep.meta.shard,
        a.runs,
        a.success,
        a.collisions,
        a.stuck,
        a.timeouts,
        a.diverged,
        rep.meta.wall_time_s
    );
    outln!(
        "wrote {}/: runs.csv summary.json summary.md",
        rep.out_dir.display()
    );
}

/// `--jobs J` capped by [`ldcbf_sim::studies::batch::cap_jobs`], with a note on
/// stderr when lowered.
fn capped_jobs(j: usize) -> usize {
    let (n, note) = ldcbf_sim::studies::batch::cap_jobs(j);
    if let Some(note) = note {
        eprintln!("note: {note}");
    }
    n
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Err(e) = ldcbf_sim::sim::cancel::install_signal_handlers() {
        return fail(anyhow::anyhow!(
            "cannot install the SIGINT/SIGTERM handlers: {e}"
        ));
    }
    match cli.command {
        Command::Batch {
            family,
            seeds,
            planner,
            perception,
            jobs,
            shard,
            out,
            closed_loop:
                LoopArgs {
                    sets,
                    solver,
                    mpc_rate,
                },
            quiet,
        } => {
            let mut req = BatchRequest::new(&family, seeds);
            req.planner = planner;
            req.perception = perception;
            if let Some(j) = jobs {
                req.jobs = capped_jobs(j);
            }
            req.shard = shard;
            req.out = out;
            req.sets = sets;
            req.solver = solver;
            req.mpc_rate = mpc_rate;
            req.progress = !quiet;
            match ldcbf_sim::studies::batch::run_batch(&req) {
                Ok(rep) => {
                    print_batch(&rep);
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
        Command::Merge {
            dirs,
            out,
            allow_partial,
        } if ldcbf_sim::studies::robustness::is_robustness_dir(&dirs[0]) => {
            match ldcbf_sim::studies::robustness::merge(&dirs, &out, allow_partial) {
                Ok(rep) => {
                    out!("{}", ldcbf_sim::studies::robustness::markdown(&rep));
                    outln!("wrote {}/: runs.csv summary.json table.md", out.display());
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
        Command::Merge {
            dirs,
            out,
            allow_partial,
        } => match ldcbf_sim::studies::batch::merge(&dirs, &out, allow_partial) {
            Ok(rep) => {
                print_batch(&rep);
                ExitCode::SUCCESS
            }
            Err(e) => fail(e),
        },
        Command::Table { dirs } => {
            let mut cols = Vec::new();
            for d in &dirs {
                match ldcbf_sim::studies::batch::read_dir(d) {
                    Ok((meta, agg, _)) => cols.push((ldcbf_sim::studies::batch::label(&meta), agg)),
                    Err(e) => return fail(e),
                }
            }
            out!("{}", ldcbf_sim::studies::batch::markdown_table(&cols));
            ExitCode::SUCCESS
        }
        Command::Deadline {
            cases,
            random,
            deadline_us,
            clock_mhz,
            sets,
            jobs,
            repeat,
            instructions,
        } => {
            let mut req = ldcbf_sim::studies::deadline::DeadlineRequest::new();
            if !cases.is_empty() {
                req.cases = cases;
            }
            req.random = random;
            req.deadline_us = deadline_us;
            req.clock_mhz = clock_mhz;
            req.sets = sets;
            req.jobs = capped_jobs(jobs);
            req.repeat = repeat;
            req.instructions = instructions;
            match ldcbf_sim::studies::deadline::run_deadline(&req) {
                Ok(rep) => {
                    out!("{}", ldcbf_sim::studies::deadline::markdown(&rep));
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
        Command::Robustness {
            cases,
            random,
            deltas,
            sets,
            jobs,
            out,
            shard,
            quiet,
        } => {
            let mut req = ldcbf_sim::studies::robustness::RobustnessRequest::new();
            req.shard = shard;
            if !cases.is_empty() {
                req.cases = cases;
            }
            req.random = random;
            req.deltas = deltas;
            req.sets = sets;
            if let Some(j) = jobs {
                req.jobs = capped_jobs(j);
            }
            req.out = out;
            req.progress = !quiet;
            match ldcbf_sim::studies::robustness::run_robustness(&req) {
                Ok(rep) => {
                    out!("{}", ldcbf_sim::studies::robustness::markdown(&rep));
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
        Command::List => {
            let dir = ldcbf_sim::scenario::scenario_dir();
            outln!("scenarios in {}:", dir.display());
            for (name, desc, _) in ldcbf_sim::scenario::list() {
                outln!("  {name:<10} {desc}");
            }
            ExitCode::SUCCESS
        }
        Command::Qp {
            command:
                QpCommand::Solve {
                    files,
                    repeat,
                    max_iter,
                    check,
                },
        } => {
            let opts = ldcbf_sim::studies::qpbench::SolveOptions {
                repeat,
                max_iter,
                check,
            };
            // Solve everything first: on any error nothing is printed but the error.
            let mut rows = Vec::with_capacity(files.len());
            for f in &files {
                match ldcbf_sim::studies::qpbench::solve_file(f, &opts) {
                    Ok(r) => rows.push(r),
                    Err(e) => return fail(e),
                }
            }
            outln!("{}", ldcbf_sim::studies::qpbench::CSV_HEADER);
            for r in &rows {
                outln!("{}", r.csv());
            }
            ExitCode::SUCCESS
        }
        Command::Run {
            scenario,
            out,
            seed,
            closed_loop:
                LoopArgs {
                    sets,
                    solver,
                    mpc_rate,
                },
            no_plots,
            no_gif,
            no_mcap,
            trajectory_every,
            export_qps,
            repeat,
        } => {
            let req = RunRequest {
                out,
                seed,
                sets,
                solver,
                mpc_rate,
                plots: !no_plots,
                gif: !no_gif,
                mcap: !no_mcap,
                trajectory_every,
                export_qps: export_qps.clone(),
                timing_repeats: repeat,
                ..RunRequest::new(&scenario)
            };
            match execute_run(&req) {
                Ok(rep) => {
                    out!("{}", ldcbf_sim::report::human_summary(&rep.summary));
                    outln!("wrote {}/: {}", rep.out_dir.display(), rep.files.join(" "));
                    if let Some(d) = export_qps {
                        outln!("wrote {} QPs to {}/", rep.result.qps.len(), d.display());
                    }
                    ExitCode::SUCCESS
                }
                Err(err) => fail(err),
            }
        }
    }
}
