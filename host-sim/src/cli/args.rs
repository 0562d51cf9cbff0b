//! The command line: its subcommands and options (clap), as `ldcbf-sim --help`
//! shows them.

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use crate::plan::Planner;
use crate::sense::Perception;
use crate::sim::{MpcRate, Solver};
use crate::studies::batch::{SeedRange, Shard};

#[derive(Parser)]
#[command(
    name = "ldcbf-sim",
    version,
    about = "Closed-loop simulator of the LDCBF footstep MPC"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Simulate a scenario and write logs and figures.
    Run(RunArgs),
    /// Dense QPs in the npz layout of tests/data/lipmwalk (P, q, G, h).
    Qp {
        #[command(subcommand)]
        command: QpCommand,
    },
    /// List the scenarios shipped in scenarios/.
    List,
    /// Run many seeds of a scenario family in parallel: runs.csv (one row per
    /// run), summary.json and summary.md (Markdown table).
    Batch(BatchArgs),
    /// Merge the shard directories of one batch or robustness study into one
    /// directory.
    Merge(MergeArgs),
    /// Print the Markdown table of one or more batch directories side by side.
    Table(TableArgs),
    /// Deadline report: per-cycle compute time p50/p99/max (ns), solver
    /// iterations (optimal / all cycles) and the margin to the deadline, per
    /// case, as a Markdown table.
    Deadline(DeadlineArgs),
    /// Robustness study: success, falls and true CoM clearance under pushes,
    /// CoM height mismatch, foot placement error and state estimation noise
    /// (two magnitudes each, see docs/robustness.md), for each safety margin
    /// delta, as Markdown tables. Disturbances of a single run are set with
    /// `run --set disturbance.<field>=value`; fields (body frame = x along the
    /// heading, y to its left): seed; push_time [s], push_period [s, 0 = once],
    /// push_forward, push_lateral [m/s, body frame], push_alternate [bool];
    /// plant_com_height [m]; foot_sigma [m, per world axis]; noise_position [m],
    /// noise_velocity [m/s], noise_heading [rad]; velocity_error [m/s, the
    /// known people's velocities handed over this wrong, with this radius].
    Robustness(RobustnessArgs),
    /// The crowd-navigation benchmark (CrowdNav, Chen et al. ICRA 2019):
    /// circle or square crossing with ORCA humans, speeds and time limit
    /// scaled to the robot's walking speed; prints one Markdown row
    /// (success, collisions, timeout, navigation time, discomfort, minimum
    /// separation; docs/results.md).
    Crowdnav(CrowdNavArgs),
}

// The options of `crowdnav` (a doc comment would be clap's help text).
#[derive(clap::Args)]
pub(crate) struct CrowdNavArgs {
    /// The layout.
    #[arg(long, value_enum, default_value = "circle")]
    pub(crate) layout: CrowdNavLayoutArg,
    /// Number of humans.
    #[arg(long, default_value_t = 5,
          value_parser = clap::value_parser!(u64).range(0..=crate::world::crowd::MAX_PEOPLE as u64))]
    pub(crate) humans: u64,
    /// Cases (seeds): `A..B` (B excluded), `A..=B`, or one seed.
    #[arg(long, default_value = "0..500")]
    pub(crate) cases: SeedRange,
    /// The humans see the robot (default: invisible, CrowdNav's setting).
    #[arg(long)]
    pub(crate) robot_visible: bool,
    /// Our controller's perception: the humans' true polygons and
    /// velocities (`oracle`) or the LiDAR with tracking.
    #[arg(long, value_enum, default_value = "oracle")]
    pub(crate) perception: CrowdNavPerception,
    /// Who walks: our controller or CrowdNav's ORCA robot.
    #[arg(long, value_enum, default_value = "controller")]
    pub(crate) robot: crate::studies::crowdnav::RobotPolicy,
    /// Worker threads [default: one per core].
    #[arg(long)]
    pub(crate) jobs: Option<usize>,
    /// Also write DIR/cases.csv (one row per case) and DIR/table.md.
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Print the table's header before the row.
    #[arg(long)]
    pub(crate) header: bool,
}

/// The CrowdNav layouts on the command line.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum CrowdNavLayoutArg {
    /// Circle crossing.
    Circle,
    /// Square crossing.
    Square,
}

/// The perceptions of `crowdnav`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum CrowdNavPerception {
    /// The true polygons and velocities.
    Oracle,
    /// The LiDAR with tracking.
    Lidar,
}

#[derive(Subcommand)]
pub(crate) enum QpCommand {
    /// Solve each file with our solver (any size: a compiled static size when
    /// one fits, the run-time-sized instance otherwise, named in the `path`
    /// column); print CSV: status, iterations, objective and the minimum solve
    /// times over the repeats (ns, solver call only): from the raw rows, with
    /// the row norms prepared outside the timing, and by the least-distance
    /// path (prepare per G and load per q, h outside the timing; the load and
    /// the prepare are timed separately). The other paths are checked against
    /// the plain solve first (an error if they disagree).
    Solve(QpSolveArgs),
}

// The options of `run` (a doc comment would be clap's help text).
#[derive(clap::Args)]
pub(crate) struct RunArgs {
    /// Scenario name (scenarios/<name>.toml) or path to a .toml file.
    pub(crate) scenario: String,
    /// Output directory [default: out/<name>, out/<name>-seed<S> for random ones].
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Seed of the scenario's random generator (e.g. `run random --seed 7`).
    #[arg(long)]
    pub(crate) seed: Option<u64>,
    #[command(flatten)]
    pub(crate) closed_loop: LoopArgs,
    /// Do not render the figures (logs and summary only).
    #[arg(long)]
    pub(crate) no_plots: bool,
    /// Do not render the animated GIF.
    #[arg(long)]
    pub(crate) no_gif: bool,
    /// Do not write run.mcap (the run for Foxglove, docs/foxglove.md).
    #[arg(long)]
    pub(crate) no_mcap: bool,
    /// Write every n-th 1 kHz sample to trajectory.csv (1 = all).
    #[arg(long, default_value_t = 10)]
    pub(crate) trajectory_every: usize,
    /// Also write every cycle's QP as DIR/cycle_NNNNN.npz (P, q, G, h), the
    /// layout `qp solve` reads.
    #[arg(long, value_name = "DIR")]
    pub(crate) export_qps: Option<PathBuf>,
    /// Timings of each controller call: `compute_ns` in cycles.csv (and the
    /// summary's compute) is the minimum of K timings on the same input and
    /// state, as in `deadline --repeat`; the run itself is the same.
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub(crate) repeat: u32,
}

// The options of `batch` (a doc comment would be clap's help text).
#[derive(clap::Args)]
pub(crate) struct BatchArgs {
    /// Scenario family: a scenario with a [generator] (name or path).
    #[arg(long, default_value = "random")]
    pub(crate) family: String,
    /// Seeds: `A..B` (B excluded), `A..=B`, or one seed.
    #[arg(long)]
    pub(crate) seeds: SeedRange,
    /// Planner (default: the scenario file's).
    #[arg(long, value_enum)]
    pub(crate) planner: Option<Planner>,
    /// Perception (default: the scenario file's).
    #[arg(long, value_enum)]
    pub(crate) perception: Option<Perception>,
    /// Worker threads [default: one per core].
    #[arg(long)]
    pub(crate) jobs: Option<usize>,
    /// Run only shard I of N (1-based) of the seeds, for studies split across
    /// machines; combine the shard directories with `merge`.
    #[arg(long, default_value = "1/1")]
    pub(crate) shard: Shard,
    /// Output directory [default: out/batch-<family>-<planner>-<perception>[-shard<I>of<N>]].
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) closed_loop: LoopArgs,
    /// No progress bar.
    #[arg(long)]
    pub(crate) quiet: bool,
}

// The options of `merge` (a doc comment would be clap's help text).
#[derive(clap::Args)]
pub(crate) struct MergeArgs {
    /// Shard directories written by `batch --shard I/N` or
    /// `robustness --shard I/N --out DIR`.
    #[arg(required = true)]
    pub(crate) dirs: Vec<PathBuf>,
    /// Output directory.
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Merge even if some seeds (runs) of the study are missing.
    #[arg(long)]
    pub(crate) allow_partial: bool,
}

// The options of `table` (a doc comment would be clap's help text).
#[derive(clap::Args)]
pub(crate) struct TableArgs {
    /// Batch directories (one column each).
    #[arg(required = true)]
    pub(crate) dirs: Vec<PathBuf>,
}

// The options of `deadline` (a doc comment would be clap's help text).
#[derive(clap::Args)]
pub(crate) struct DeadlineArgs {
    /// Cases `NAME[+rrt_star|+none][@SEED]` (a shipped scenario or a path),
    /// e.g. `maze+none`, `crowded@0` [default: the shipped cases,
    /// `ldcbf_sim::studies::deadline::SHIPPED_CASES`, and `large-map`].
    #[arg(value_name = "CASES")]
    pub(crate) cases: Vec<crate::studies::deadline::Case>,
    /// Also run seeds 0..N of the `random` family (pooled into one row).
    #[arg(long, default_value_t = 0, value_name = "N",
          value_parser = clap::value_parser!(u64).range(..=crate::studies::batch::MAX_SEEDS))]
    pub(crate) random: u64,
    /// Deadline per control cycle, µs (250 = the 100,000
    /// instructions at 400 MHz).
    #[arg(long, default_value_t = crate::studies::deadline::DEFAULT_DEADLINE_US, value_name = "D")]
    pub(crate) deadline_us: f64,
    /// Target clock, MHz, to turn instruction counts into time.
    #[arg(long, default_value_t = crate::studies::deadline::DEFAULT_CLOCK_MHZ, value_name = "F")]
    pub(crate) clock_mhz: f64,
    /// Override a scenario field for every case (as for `run`).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_set)]
    pub(crate) sets: Vec<(String, String)>,
    /// Worker threads (more than one shares the cores between runs, which
    /// shows in the wall-clock times).
    #[arg(long, default_value_t = 1)]
    pub(crate) jobs: usize,
    /// Timings of each control cycle: the controller call is timed K times
    /// on the same input and state (clones of the controller) and the
    /// cycle's compute time is the minimum, so a preemption does not count
    /// and the max is the hardest cycle. The closed loops (cycles, statuses,
    /// iterations) are the same for every K; the controller's share of the
    /// study's time grows K-fold. A lower bound: back-to-back timings of one
    /// input run with warm caches. With --jobs > 1 the runs still share the
    /// cores.
    #[arg(long, default_value_t = 1, value_name = "K")]
    pub(crate) repeat: u32,
    /// Per-cycle instruction counts of the firmware in QEMU (CSV
    /// `cycle,status,iterations,instructions`, written by
    /// tests/firmware_qemu.rs to firmware/target/instructions.csv).
    #[arg(long, value_name = "FILE")]
    pub(crate) instructions: Option<PathBuf>,
}

// The options of `robustness` (a doc comment would be clap's help text).
#[derive(clap::Args)]
pub(crate) struct RobustnessArgs {
    /// Cases `NAME[+rrt_star|+none][@SEED]` [default: the deadline study's
    /// shipped cases].
    #[arg(value_name = "CASES")]
    pub(crate) cases: Vec<crate::studies::deadline::Case>,
    /// Also run seeds 0..N of the `random` family.
    #[arg(long, default_value_t = 200, value_name = "N",
          value_parser = clap::value_parser!(u64).range(..=crate::studies::batch::MAX_SEEDS))]
    pub(crate) random: u64,
    /// Safety margins delta, m, comma separated (each replaces the files' own).
    #[arg(long = "delta", value_delimiter = ',', default_values_t = crate::studies::robustness::DEFAULT_DELTAS)]
    pub(crate) deltas: Vec<f64>,
    /// Override a scenario field for every run (as for `run`), e.g. `l_max=0.3`.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_set)]
    pub(crate) sets: Vec<(String, String)>,
    /// Worker threads [default: one per core].
    #[arg(long)]
    pub(crate) jobs: Option<usize>,
    /// Also write DIR/runs.csv (every run), DIR/table.md and
    /// DIR/summary.json (what the study is, for `merge`).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Run only shard I of N (1-based) of the runs (interleaved in the
    /// order condition, delta, case), for studies split across machines;
    /// needs --out; combine the shard directories with `merge`.
    #[arg(long, default_value = "1/1")]
    pub(crate) shard: Shard,
    /// No progress bar.
    #[arg(long)]
    pub(crate) quiet: bool,
}

// The options of `qp solve` (a doc comment would be clap's help text).
#[derive(clap::Args)]
pub(crate) struct QpSolveArgs {
    /// npz files of the qpbenchmark layout (P, q and any of G, h, A, b,
    /// lb, ub).
    #[arg(required = true)]
    pub(crate) files: Vec<PathBuf>,
    /// Timed repeats per file (the minimum is printed).
    #[arg(long, default_value_t = 1)]
    pub(crate) repeat: usize,
    /// Iteration budget per solve.
    #[arg(long, default_value_t = 1000)]
    pub(crate) max_iter: u32,
    /// Also solve each file with Clarabel and check the agreement (primal
    /// 1e-6 scaled, objective 1e-6, feasibility verdict, Farkas
    /// certificate); columns clarabel_dx, clarabel_dobj; a disagreement is
    /// an error.
    #[arg(long)]
    pub(crate) check: bool,
}

/// The closed-loop options shared by `run` and `batch`.
#[derive(clap::Args)]
pub(crate) struct LoopArgs {
    /// Override a scenario field (for every run): `key=value` with a TOML value,
    /// e.g. `delta=0.3`, `controller.gamma=0.5`, `time_limit=200`, `goal=[5,5]`,
    /// `disturbance.push_lateral=0.1` (disturbance fields: `robustness --help`).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_set)]
    pub(crate) sets: Vec<(String, String)>,
    /// QP solver inside the controller.
    #[arg(long, value_enum, default_value = "own")]
    pub(crate) solver: Solver,
    /// Controller rate: a rate in Hz (20 = the paper's), or `step` (once per step).
    #[arg(long, default_value = "20")]
    pub(crate) mpc_rate: MpcRate,
}

/// Parses one `--set KEY=VALUE` into the trimmed key and value.
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

/// `--jobs J` capped by [`crate::studies::batch::cap_jobs`], with a note on
/// stderr when lowered.
pub(crate) fn capped_jobs(j: usize) -> usize {
    let (n, note) = crate::studies::batch::cap_jobs(j);
    if let Some(note) = note {
        eprintln!("note: {note}");
    }
    n
}
