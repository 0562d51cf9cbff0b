//! `ldcbf-sim deadline`: the controller's per-cycle cost against a real-time
//! deadline, over a set of closed loops.
//!
//! A study is a list of [`Case`]s (a shipped scenario or a path, optionally with
//! a planner and a seed: `maze+rrt_star`, `crowded@0`, `random@17`), each run to
//! its end exactly as `ldcbf-sim run` would (own solver, 20 Hz, no figures), and
//! optionally the first `N` seeds of the `random` family. Of every control cycle
//! it keeps the status, where the command came from, the solver iterations
//! (`CycleInfo::iterations`, the whole cycle's adds plus drops, the priority
//! scheme's solves included) and the wall-clock time of the controller call
//! (measured by the simulator around `Controller::step_with` only). With
//! `--repeat K` ([`DeadlineRequest::repeat`], [`SimOptions::timing_repeats`])
//! each cycle's call is timed `K` times on the same input and the same
//! controller state (clones made just before the call) and its time is the
//! minimum: the cycle's compute without the scheduler's noise. The closed loops,
//! hence the cycles, statuses and iterations, are the same for every `K`.
//!
//! Two kinds of cost, reported side by side by [`markdown`]:
//!
//! * **Deterministic**: the iteration counts. They do not depend on the machine
//!   or its load, so CI can assert them (`tests/deadline_iterations.rs`)
//!   against the configured budgets, `max_iter` per QP solve and
//!   `max_iter_cycle` per control cycle. The firmware's instruction counts in
//!   QEMU (`tests/firmware_qemu.rs`) are the other deterministic measure; they
//!   exist only for the 240 recorded `paper` cycles the firmware replays, and are
//!   shown when a CSV of them is given ([`read_instructions`]).
//! * **Wall clock**: p50 / p99 / max of the compute time per cycle (ns), the
//!   cycle of the max ([`CostStats::slowest`]) and the margin `deadline - max`.
//!   These are of this machine and this build. With one timing per cycle
//!   (`K = 1`) they are also of its load: a preemption during one call shows as
//!   the maximum. With `K > 1` the max is the hardest cycle's compute, as long
//!   as one of its `K` timings ran undisturbed.
//!
//! The default deadline is the real-time target: 100,000 instructions
//! per cycle at 400 MHz (one instruction per clock), i.e. 250 µs
//! ([`DEFAULT_DEADLINE_US`], [`DEFAULT_CLOCK_MHZ`]).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use ldcbf_controller::{CommandSource, CycleStatus};
use rayon::prelude::*;

use crate::report::{ComputeStats, compute_stats};
use crate::scenario::{LoadOptions, Planner, Scenario, load};
use crate::sim::{Outcome, SimOptions, run};

/// Default deadline per control cycle, µs: the 100,000 instructions at
/// 400 MHz.
pub const DEFAULT_DEADLINE_US: f64 = 250.0;

/// Default clock of the target processor, MHz, used to turn instruction counts
/// into time (one instruction per clock).
pub const DEFAULT_CLOCK_MHZ: f64 = 400.0;

/// The shipped closed loops a deadline study runs by default (and the CI
/// check): every shipped scenario except the seeded families (`random`, which
/// is `--random N`, and `corridor`, `doorway`, `cup`, `wall-start`, `clutter`,
/// `thin`, which `batch` and `tests/sim_body.rs` run), `maze` and `trap` both without and with RRT* subgoals
/// (`maze` ships with them, `maze+none` is the MPC alone),
/// `crowded` with its seed 0, the LiDAR regressions `cup-mouth` and
/// `corner-start`.
pub const SHIPPED_CASES: [&str; 10] = [
    "simple",
    "circles",
    "paper",
    "maze+none",
    "maze+rrt_star",
    "trap",
    "trap+rrt_star",
    "crowded@0",
    "cup-mouth",
    "corner-start",
];

/// The large maps a deadline study runs by default besides [`SHIPPED_CASES`]
/// (kept out of them, which the iteration and budget tests run in debug
/// builds): `large-map`, 10,000 polygons, whose cycles cost what a small map's
/// do because the controller is handed only the map index's candidates
/// ([`crate::obstacle_index`]; `tests/obstacle_index.rs` runs it).
pub const LARGE_MAP_CASES: [&str; 1] = ["large-map"];

/// The scenario family of `--random N`.
pub const RANDOM_FAMILY: &str = "random";

/// Header of the per-cycle instruction CSV that `tests/firmware_qemu.rs` writes
/// (`firmware/target/instructions.csv`) and [`read_instructions`] reads: one row
/// per replayed cycle, `status` as `CycleStatus::name`.
pub const INSTRUCTIONS_HEADER: &str = "cycle,status,iterations,instructions";

/// One closed loop of a study: `NAME[+PLANNER][@SEED]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Case {
    /// Scenario name (`scenarios/<name>.toml`) or path to a `.toml` file.
    pub scenario: String,
    /// Planner override (`+rrt_star`, `+none`); `None` = the file's.
    pub planner: Option<Planner>,
    /// Seed of the scenario's generator, planner and LiDAR (`@S`); `None` = the
    /// file's.
    pub seed: Option<u64>,
}

impl Case {
    /// A case with the file's planner and seed.
    pub fn new(scenario: &str) -> Self {
        Case {
            scenario: scenario.into(),
            planner: None,
            seed: None,
        }
    }

    /// The case as written on the command line (`maze+rrt_star`, `random@7`).
    pub fn label(&self) -> String {
        let mut s = self.scenario.clone();
        if let Some(p) = self.planner {
            s += "+";
            s += p.name();
        }
        if let Some(seed) = self.seed {
            s += &format!("@{seed}");
        }
        s
    }

    /// Loads and validates the scenario: `sets` first, then this case's planner
    /// (so `maze+rrt_star` wins over a global `--set planner=none`).
    pub fn load(&self, sets: &[(String, String)]) -> Result<Scenario> {
        let mut all = sets.to_vec();
        if let Some(p) = self.planner {
            all.push(("planner".into(), format!("\"{}\"", p.name())));
        }
        load(
            &self.scenario,
            &LoadOptions {
                seed: self.seed,
                sets: all,
            },
        )
        .with_context(|| format!("case {}", self.label()))
    }
}

impl core::fmt::Display for Case {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.label())
    }
}

impl core::str::FromStr for Case {
    type Err = String;
    /// `NAME[+PLANNER][@SEED]`: `maze`, `maze+rrt_star`, `crowded@3`,
    /// `trap+rrt_star@1`, or a path (which must not contain `@`).
    fn from_str(s: &str) -> Result<Self, String> {
        let syntax = || {
            format!(
                "expected a case NAME[+rrt_star|+none][@SEED] (e.g. maze+rrt_star, crowded@0), got {s:?}"
            )
        };
        let mut rest = s.trim();
        let mut seed = None;
        if let Some((a, b)) = rest.rsplit_once('@') {
            seed = Some(b.trim().parse::<u64>().map_err(|_| syntax())?);
            rest = a;
        }
        let mut planner = None;
        if let Some((a, b)) = rest.rsplit_once('+') {
            let looks_like_path = b.contains(['/', '\\', '.']);
            if !looks_like_path {
                planner = Some(match b.trim() {
                    "rrt_star" => Planner::RrtStar,
                    "none" => Planner::None,
                    other => {
                        return Err(format!(
                            "unknown planner {other:?} in case {s:?} (expected rrt_star or none)"
                        ));
                    }
                });
                rest = a;
            }
        }
        let rest = rest.trim();
        if rest.is_empty() {
            return Err(syntax());
        }
        Ok(Case {
            scenario: rest.to_string(),
            planner,
            seed,
        })
    }
}

/// The default cases ([`SHIPPED_CASES`]).
pub fn shipped_cases() -> Vec<Case> {
    SHIPPED_CASES
        .iter()
        .map(|s| s.parse().expect("the shipped cases parse"))
        .collect()
}

/// Seeds `0..n` of the `random` family (known map, the paper's defaults).
pub fn random_cases(n: u64) -> Vec<Case> {
    (0..n)
        .map(|seed| Case {
            scenario: RANDOM_FAMILY.into(),
            planner: None,
            seed: Some(seed),
        })
        .collect()
}

/// The cost of one control cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleCost {
    /// Cycle index in its run, from 0.
    pub index: usize,
    /// Simulated time of the call, s.
    pub time: f64,
    /// The cycle's status.
    pub status: CycleStatus,
    /// Where its command came from.
    pub source: CommandSource,
    /// Solver iterations of the whole cycle (adds plus drops, the priority
    /// scheme's solves included).
    pub iterations: u32,
    /// Wall-clock time of the controller call, ns.
    pub compute_ns: u64,
}

impl CycleCost {
    /// The command is a fallback (previous plan or capture step): the QP and,
    /// for an infeasible cycle, the priority scheme did not produce a plan
    /// (budget or numerical failure). For such cycles the controller reports
    /// only the nominal solve's iterations (`CycleInfo::iterations` is not
    /// increased by a relaxation that failed).
    pub fn is_fallback(&self) -> bool {
        matches!(
            self.source,
            CommandSource::PreviousPlan | CommandSource::CaptureStep
        )
    }
}

/// One finished closed loop of a study.
#[derive(Clone, Debug)]
pub struct CaseRun {
    /// The case.
    pub case: Case,
    /// Its label ([`Case::label`]; `random@S` for the random seeds).
    pub label: String,
    /// The scenario's seed (the file's when the case gives none).
    pub seed: u64,
    /// The configured iteration budget of one QP solve.
    pub max_iter: u32,
    /// The configured iteration budget of one control cycle.
    pub max_iter_cycle: u32,
    /// Why the run ended.
    pub outcome: Outcome,
    /// Every control cycle, in order.
    pub cycles: Vec<CycleCost>,
}

/// Loads every case (all errors before any simulation), then simulates them
/// with `jobs` worker threads, one timing per controller call. The results are
/// in the order of `cases` and do not depend on `jobs` (except the wall-clock
/// times).
pub fn run_cases(cases: &[Case], sets: &[(String, String)], jobs: usize) -> Result<Vec<CaseRun>> {
    run_cases_timed(cases, sets, jobs, 1)
}

/// [`run_cases`] with `repeat` timings of each controller call
/// ([`SimOptions::timing_repeats`]: each cycle's `compute_ns` is the minimum).
/// Everything but the wall-clock times is the same for every `repeat >= 1`.
pub fn run_cases_timed(
    cases: &[Case],
    sets: &[(String, String)],
    jobs: usize,
    repeat: u32,
) -> Result<Vec<CaseRun>> {
    if jobs == 0 {
        bail!("--jobs must be >= 1");
    }
    if repeat == 0 {
        bail!("--repeat must be >= 1 (timings of each control cycle), got 0");
    }
    let scenarios: Vec<Scenario> = cases.iter().map(|c| c.load(sets)).collect::<Result<_>>()?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .context("cannot start the worker threads")?;
    // No clearances: the study does not report them, and the walk is the same.
    let opts = SimOptions {
        record_scans: false,
        record_clearance: false,
        timing_repeats: repeat,
        ..SimOptions::default()
    };
    let runs: Vec<Result<CaseRun>> = pool.install(|| {
        cases
            .par_iter()
            .zip(scenarios.par_iter())
            .map(|(case, sc)| {
                let r = run(sc, opts).with_context(|| format!("case {}", case.label()))?;
                Ok(CaseRun {
                    case: case.clone(),
                    label: case.label(),
                    seed: sc.seed,
                    max_iter: sc.config.max_iter,
                    max_iter_cycle: sc.config.max_iter_cycle,
                    outcome: r.outcome,
                    cycles: r
                        .cycles
                        .iter()
                        .map(|c| CycleCost {
                            index: c.index,
                            time: c.time,
                            status: c.output.status,
                            source: c.output.info.source,
                            iterations: c.output.info.iterations,
                            compute_ns: c.compute_ns,
                        })
                        .collect(),
                })
            })
            .collect()
    });
    runs.into_iter().collect()
}

/// Where a worst case occurred.
#[derive(Clone, Debug, PartialEq)]
pub struct Worst {
    /// The value (iterations).
    pub value: u32,
    /// The run's label.
    pub label: String,
    /// The cycle's index in its run.
    pub cycle: usize,
    /// The cycle's simulated time, s.
    pub time: f64,
    /// The cycle's status.
    pub status: CycleStatus,
}

impl core::fmt::Display for Worst {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} in {} cycle {} (t = {:.2} s, {})",
            self.value,
            self.label,
            self.cycle,
            self.time,
            self.status.name()
        )
    }
}

/// The cycle with the longest compute time of a group of runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Slowest {
    /// Its compute time, ns ([`CycleCost::compute_ns`]).
    pub compute_ns: u64,
    /// The run's label.
    pub label: String,
    /// The cycle's index in its run, from 0 (data row `cycle + 1` of the
    /// `cycles.csv` that `ldcbf-sim run` writes).
    pub cycle: usize,
    /// The cycle's simulated time, s.
    pub time: f64,
    /// The cycle's status.
    pub status: CycleStatus,
    /// Its solver iterations.
    pub iterations: u32,
}

impl core::fmt::Display for Slowest {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} cycle {} (t = {:.2} s, {}, {} it)",
            self.label,
            self.cycle,
            self.time,
            self.status.name(),
            self.iterations
        )
    }
}

/// The per-cycle cost of a group of runs.
#[derive(Clone, Debug, PartialEq)]
pub struct CostStats {
    /// Runs.
    pub runs: usize,
    /// Control cycles.
    pub cycles: usize,
    /// Cycles whose nominal QP was not solved (status not `optimal`).
    pub non_optimal: usize,
    /// Of those, `budget_exhausted`.
    pub budget_exhausted: usize,
    /// Of those, `numerical_failure`.
    pub numerical_failure: usize,
    /// Of those, `invalid_input` (the run diverged).
    pub invalid_input: usize,
    /// Cycles whose command is a fallback ([`CycleCost::is_fallback`]).
    pub fallback: usize,
    /// Compute time per cycle, pooled over the group's cycles (nearest rank).
    pub compute: ComputeStats,
    /// Compute time of the non-optimal cycles only (the priority scheme's path).
    pub compute_non_optimal: ComputeStats,
    /// Cycles whose compute time exceeded the deadline.
    pub over_deadline: usize,
    /// The cycle of `compute.max_ns` (the first one on ties), if any.
    pub slowest: Option<Slowest>,
    /// Most iterations of an `optimal` cycle (one QP solve), if any.
    pub worst_optimal: Option<Worst>,
    /// Most iterations of any cycle (the priority scheme included), if any.
    pub worst_all: Option<Worst>,
    /// Smallest configured `max_iter` over the runs.
    pub max_iter: u32,
    /// Smallest configured `max_iter_cycle` over the runs.
    pub max_iter_cycle: u32,
    /// Runs that reached the goal.
    pub reached: usize,
}

fn worst_of<'a>(
    runs: &[&'a CaseRun],
    keep: impl Fn(&CycleCost) -> bool,
) -> Option<(&'a CaseRun, &'a CycleCost)> {
    let mut best: Option<(&CaseRun, &CycleCost)> = None;
    for r in runs {
        for c in r.cycles.iter().filter(|c| keep(c)) {
            // First occurrence on ties (runs in order, cycles in order).
            if best.is_none_or(|(_, b)| c.iterations > b.iterations) {
                best = Some((r, c));
            }
        }
    }
    best
}

fn slowest(runs: &[&CaseRun]) -> Option<Slowest> {
    let mut best: Option<(&CaseRun, &CycleCost)> = None;
    for r in runs {
        for c in &r.cycles {
            if best.is_none_or(|(_, b)| c.compute_ns > b.compute_ns) {
                best = Some((r, c));
            }
        }
    }
    best.map(|(r, c)| Slowest {
        compute_ns: c.compute_ns,
        label: r.label.clone(),
        cycle: c.index,
        time: c.time,
        status: c.status,
        iterations: c.iterations,
    })
}

/// The statistics of a group of runs; `deadline_ns` counts the cycles over it.
pub fn cost_stats(runs: &[&CaseRun], deadline_ns: u64) -> CostStats {
    let all = || runs.iter().flat_map(|r| r.cycles.iter());
    let count = |f: &dyn Fn(&CycleCost) -> bool| all().filter(|c| f(c)).count();
    let ns: Vec<u64> = all().map(|c| c.compute_ns).collect();
    let worst = |keep: &dyn Fn(&CycleCost) -> bool| {
        worst_of(runs, keep).map(|(r, c)| Worst {
            value: c.iterations,
            label: r.label.clone(),
            cycle: c.index,
            time: c.time,
            status: c.status,
        })
    };
    CostStats {
        runs: runs.len(),
        cycles: ns.len(),
        non_optimal: count(&|c| !c.status.is_optimal()),
        budget_exhausted: count(&|c| c.status == CycleStatus::BudgetExhausted),
        numerical_failure: count(&|c| c.status == CycleStatus::NumericalFailure),
        invalid_input: count(&|c| matches!(c.status, CycleStatus::InvalidInput(_))),
        fallback: count(&|c| c.is_fallback()),
        compute: compute_stats(&ns),
        compute_non_optimal: compute_stats(
            &all()
                .filter(|c| !c.status.is_optimal())
                .map(|c| c.compute_ns)
                .collect::<Vec<_>>(),
        ),
        over_deadline: count(&|c| c.compute_ns > deadline_ns),
        slowest: slowest(runs),
        worst_optimal: worst(&|c| c.status.is_optimal()),
        worst_all: worst(&|_| true),
        max_iter: runs.iter().map(|r| r.max_iter).min().unwrap_or(0),
        max_iter_cycle: runs.iter().map(|r| r.max_iter_cycle).min().unwrap_or(0),
        reached: runs
            .iter()
            .filter(|r| r.outcome == Outcome::GoalReached)
            .count(),
    }
}

/// The firmware's instruction counts per cycle (a CSV with
/// [`INSTRUCTIONS_HEADER`]), summarised.
#[derive(Clone, Debug, PartialEq)]
pub struct FirmwareInstructions {
    /// The file read.
    pub source: PathBuf,
    /// Cycles in it.
    pub cycles: usize,
    /// Cycles whose status was not `optimal`.
    pub non_optimal: usize,
    /// Most instructions of an `optimal` cycle, if any.
    pub max_optimal: Option<u64>,
    /// Most instructions of any cycle.
    pub max_all: u64,
    /// The cycle of `max_all` (the file's `cycle` column; the first on ties).
    pub max_all_cycle: u64,
    /// Its status, as written in the file.
    pub max_all_status: String,
    /// Most iterations of an `optimal` cycle, if any.
    pub iterations_optimal: Option<u32>,
    /// Most iterations of any cycle.
    pub iterations_all: u32,
}

/// Reads a per-cycle instruction CSV ([`INSTRUCTIONS_HEADER`], as written by
/// `tests/firmware_qemu.rs`). Any malformed line is an error naming the file
/// and line.
pub fn read_instructions(path: &Path) -> Result<FirmwareInstructions> {
    if path.is_dir() {
        bail!(
            "{}: is a directory, not an instruction CSV (firmware/target/instructions.csv)",
            path.display()
        );
    }
    let bytes = std::fs::read(path)
        .with_context(|| format!("{}: cannot read the instruction counts", path.display()))?;
    let text = String::from_utf8(bytes).map_err(|_| {
        anyhow!(
            "{}: not a text file (invalid UTF-8), expected the instruction CSV",
            path.display()
        )
    })?;
    if text.trim().is_empty() {
        bail!(
            "{}: empty file, expected the header {INSTRUCTIONS_HEADER:?}",
            path.display()
        );
    }
    if !text.ends_with('\n') {
        bail!(
            "{}:{}: the last line ends without a newline (truncated file?)",
            path.display(),
            text.lines().count()
        );
    }
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("").trim();
    if header != INSTRUCTIONS_HEADER {
        bail!(
            "{}:1: expected the header {INSTRUCTIONS_HEADER:?} (written by tests/firmware_qemu.rs), got {header:?}",
            path.display()
        );
    }
    let mut out = FirmwareInstructions {
        source: path.to_path_buf(),
        cycles: 0,
        non_optimal: 0,
        max_optimal: None,
        max_all: 0,
        max_all_cycle: 0,
        max_all_status: String::new(),
        iterations_optimal: None,
        iterations_all: 0,
    };
    for (i, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let bad = |what: &str| anyhow!("{}:{}: {what} in {line:?}", path.display(), i + 2);
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 4 {
            return Err(bad("expected 4 fields"));
        }
        let cycle: u64 = f[0].parse().map_err(|_| bad("bad cycle"))?;
        let iterations: u32 = f[2].parse().map_err(|_| bad("bad iterations"))?;
        let instructions: u64 = f[3].parse().map_err(|_| bad("bad instructions"))?;
        if out.cycles == 0 || instructions > out.max_all {
            out.max_all = instructions;
            out.max_all_cycle = cycle;
            out.max_all_status = f[1].to_string();
        }
        out.cycles += 1;
        out.iterations_all = out.iterations_all.max(iterations);
        if f[1] == "optimal" {
            out.max_optimal = Some(out.max_optimal.unwrap_or(0).max(instructions));
            out.iterations_optimal = Some(out.iterations_optimal.unwrap_or(0).max(iterations));
        } else {
            out.non_optimal += 1;
        }
    }
    if out.cycles == 0 {
        bail!("{}: no cycles", path.display());
    }
    Ok(out)
}

/// What `ldcbf-sim deadline` needs.
#[derive(Clone, Debug)]
pub struct DeadlineRequest {
    /// Named cases, one table row each.
    pub cases: Vec<Case>,
    /// Seeds `0..random` of the `random` family, pooled into one row.
    pub random: u64,
    /// `--set key=value` overrides for every case.
    pub sets: Vec<(String, String)>,
    /// Deadline per control cycle, µs.
    pub deadline_us: f64,
    /// Target clock, MHz (instructions to time).
    pub clock_mhz: f64,
    /// Worker threads. More than one makes the runs share the cores, which
    /// shows in the wall-clock times (not in the iterations).
    pub jobs: usize,
    /// Timings of each control cycle, `>= 1`; the cycle's compute time is their
    /// minimum ([`SimOptions::timing_repeats`]). The controller's share of the
    /// study's time grows `repeat`-fold; the cycles, statuses and iterations do
    /// not change.
    pub repeat: u32,
    /// A per-cycle instruction CSV of the firmware ([`read_instructions`]).
    pub instructions: Option<PathBuf>,
}

impl DeadlineRequest {
    /// The CLI's defaults: the shipped cases and [`LARGE_MAP_CASES`], no
    /// random seeds, 250 µs at 400 MHz, one job, one timing per cycle, no
    /// instruction file.
    pub fn new() -> Self {
        let mut cases = shipped_cases();
        cases.extend(LARGE_MAP_CASES.iter().map(|s| Case::new(s)));
        DeadlineRequest {
            cases,
            random: 0,
            sets: Vec::new(),
            deadline_us: DEFAULT_DEADLINE_US,
            clock_mhz: DEFAULT_CLOCK_MHZ,
            jobs: 1,
            repeat: 1,
            instructions: None,
        }
    }
}

impl Default for DeadlineRequest {
    fn default() -> Self {
        Self::new()
    }
}

/// One row of the report.
#[derive(Clone, Debug)]
pub struct DeadlineRow {
    /// Case label, or `random@0..N` for the pooled random seeds, or `all`.
    pub label: String,
    /// Its statistics.
    pub stats: CostStats,
}

/// A finished deadline study.
#[derive(Clone, Debug)]
pub struct DeadlineReport {
    /// The deadline, ns.
    pub deadline_ns: u64,
    /// The target clock, MHz.
    pub clock_mhz: f64,
    /// One row per named case, then the pooled random seeds, then `all` (when
    /// there is more than one row before it).
    pub rows: Vec<DeadlineRow>,
    /// Every run, in order (named cases first).
    pub runs: Vec<CaseRun>,
    /// The firmware's instruction counts, when a file was given.
    pub instructions: Option<FirmwareInstructions>,
    /// Wall-clock time of the study, s.
    pub wall_time_s: f64,
    /// Worker threads used.
    pub jobs: usize,
    /// Timings per control cycle (the minimum counts).
    pub repeat: u32,
}

impl DeadlineReport {
    /// The instruction budget per cycle: the deadline at the target clock.
    pub fn instruction_budget(&self) -> u64 {
        (self.deadline_ns as f64 * self.clock_mhz / 1e3).round() as u64
    }
}

/// Runs a deadline study (see the module docs). Bad arguments, an unknown
/// scenario or an unreadable instruction file fail before any simulation.
pub fn run_deadline(req: &DeadlineRequest) -> Result<DeadlineReport> {
    if !(req.deadline_us.is_finite() && req.deadline_us > 0.0) {
        bail!(
            "--deadline-us must be a positive number of microseconds, got {}",
            req.deadline_us
        );
    }
    if !(req.clock_mhz.is_finite() && req.clock_mhz > 0.0) {
        bail!(
            "--clock-mhz must be a positive number, got {}",
            req.clock_mhz
        );
    }
    if req.repeat == 0 {
        bail!("--repeat must be >= 1 (timings of each control cycle), got 0");
    }
    if req.cases.is_empty() && req.random == 0 {
        bail!("nothing to run: give scenarios or --random N");
    }
    let instructions = req
        .instructions
        .as_deref()
        .map(read_instructions)
        .transpose()?;
    let deadline_ns = (req.deadline_us * 1e3).round() as u64;
    let mut cases = req.cases.clone();
    cases.extend(random_cases(req.random));
    let t0 = Instant::now();
    let runs = run_cases_timed(&cases, &req.sets, req.jobs, req.repeat)?;
    let wall_time_s = t0.elapsed().as_secs_f64();
    let named = req.cases.len();
    let mut rows: Vec<DeadlineRow> = runs[..named]
        .iter()
        .map(|r| DeadlineRow {
            label: r.label.clone(),
            stats: cost_stats(&[r], deadline_ns),
        })
        .collect();
    if req.random > 0 {
        let group: Vec<&CaseRun> = runs[named..].iter().collect();
        rows.push(DeadlineRow {
            label: format!("{RANDOM_FAMILY}@0..{}", req.random),
            stats: cost_stats(&group, deadline_ns),
        });
    }
    if rows.len() > 1 {
        let group: Vec<&CaseRun> = runs.iter().collect();
        rows.push(DeadlineRow {
            label: "all".into(),
            stats: cost_stats(&group, deadline_ns),
        });
    }
    Ok(DeadlineReport {
        deadline_ns,
        clock_mhz: req.clock_mhz,
        rows,
        runs,
        instructions,
        wall_time_s,
        jobs: req.jobs,
        repeat: req.repeat,
    })
}

fn pct(part: f64, whole: f64) -> String {
    if whole > 0.0 {
        format!("{:.0} %", 100.0 * part / whole)
    } else {
        "n/a".into()
    }
}

/// The report as Markdown: a few header lines, the table (one row per case,
/// the pooled random seeds, `all`), the worst cases and the budgets.
pub fn markdown(rep: &DeadlineReport) -> String {
    let mut s = String::new();
    let budget = rep.instruction_budget();
    let timing = if rep.repeat > 1 {
        format!(
            "compute = wall clock around the controller call only, each cycle's minimum of {} timings \
             on the same input and state (preemption filtered: the max is the hardest cycle)",
            rep.repeat
        )
    } else {
        "compute = wall clock around the controller call only, one timing per cycle (a preemption \
         shows as the max; --repeat K takes each cycle's minimum of K)"
            .to_string()
    };
    let _ = writeln!(
        s,
        "deadline {} ns per control cycle (= {budget} instructions at {} MHz); {timing}; {} build, \
         {} job(s), this machine (indicative; the iteration counts are deterministic); study wall \
         time {:.1} s",
        rep.deadline_ns,
        rep.clock_mhz,
        if cfg!(debug_assertions) {
            "DEBUG"
        } else {
            "release"
        },
        rep.jobs,
        rep.wall_time_s
    );
    s.push('\n');
    s += "| case | runs | reached | cycles | non-optimal | compute p50 [ns] | p99 [ns] | max [ns] \
          | max at | over deadline | iterations max: optimal / all | instructions max | margin [ns] |\n";
    s += "|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---|---:|\n";
    let it = |w: &Option<Worst>| w.as_ref().map_or("-".to_string(), |w| w.value.to_string());
    for row in &rep.rows {
        let st = &row.stats;
        let margin = rep.deadline_ns as i64 - st.compute.max_ns as i64;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} / {} | n/a | {margin} ({}){} |",
            row.label,
            st.runs,
            st.reached,
            st.cycles,
            st.non_optimal,
            st.compute.p50_ns,
            st.compute.p99_ns,
            st.compute.max_ns,
            st.slowest
                .as_ref()
                .map_or("-".to_string(), ToString::to_string),
            st.over_deadline,
            it(&st.worst_optimal),
            it(&st.worst_all),
            pct(margin as f64, rep.deadline_ns as f64),
            if margin < 0 { " MISSED" } else { "" },
        );
    }
    if let Some(fw) = &rep.instructions {
        let max_ns = fw.max_all as f64 * 1e3 / rep.clock_mhz;
        let margin = rep.deadline_ns as f64 - max_ns;
        let _ = writeln!(
            s,
            "| firmware (QEMU, recorded cycles) | 1 | - | {} | {} | - | - | {:.0} at {} MHz | cycle {} ({}) | - | {} / {} | {} / {} | {:.0} ({}){} |",
            fw.cycles,
            fw.non_optimal,
            max_ns,
            rep.clock_mhz,
            fw.max_all_cycle,
            fw.max_all_status,
            fw.iterations_optimal
                .map_or("-".to_string(), |v| v.to_string()),
            fw.iterations_all,
            fw.max_optimal.map_or("-".to_string(), |v| v.to_string()),
            fw.max_all,
            margin,
            pct(margin, rep.deadline_ns as f64),
            if margin < 0.0 { " MISSED" } else { "" },
        );
    }
    s.push('\n');
    if let Some(total) = rep.rows.last().map(|r| &r.stats) {
        let worst = |w: &Option<Worst>, budget: u32| match w {
            Some(w) => format!(
                "{w}: {} of {budget}, margin {} ({})",
                w.value,
                i64::from(budget) - i64::from(w.value),
                pct(f64::from(budget) - f64::from(w.value), f64::from(budget))
            ),
            None => "none".into(),
        };
        let _ = writeln!(
            s,
            "- iterations (adds + drops), worst optimal cycle (one QP solve, budget `max_iter` = {}): {}",
            total.max_iter,
            worst(&total.worst_optimal, total.max_iter)
        );
        let _ = writeln!(
            s,
            "- iterations, worst cycle (priority scheme included, budget `max_iter_cycle` = {}): {}",
            total.max_iter_cycle,
            worst(&total.worst_all, total.max_iter_cycle)
        );
        let _ = writeln!(
            s,
            "- non-optimal cycles {} of {}: budget_exhausted {}, numerical_failure {}, invalid_input {}; fallback commands (previous plan / capture step) {}; their compute p50 {} ns, max {} ns",
            total.non_optimal,
            total.cycles,
            total.budget_exhausted,
            total.numerical_failure,
            total.invalid_input,
            total.fallback,
            total.compute_non_optimal.p50_ns,
            total.compute_non_optimal.max_ns
        );
        if let Some(w) = &total.slowest {
            let _ = writeln!(
                s,
                "- slowest cycle: {} ns, {w} (`ldcbf-sim run` of that case logs it in cycles.csv: \
                 data row {}, `t` = {:.3}){}",
                w.compute_ns,
                w.cycle + 1,
                w.time,
                if rep.repeat > 1 {
                    format!("; minimum of {} timings", rep.repeat)
                } else {
                    "; one timing, maybe a preemption".to_string()
                }
            );
        }
    }
    match &rep.instructions {
        Some(fw) => {
            let _ = writeln!(
                s,
                "- instructions: {} ({} cycles replayed by the firmware in QEMU, `-icount`, deterministic); budget {budget} per cycle",
                fw.source.display(),
                fw.cycles
            );
        }
        None => {
            s += "- instructions max: n/a (see firmware/README.md; `--instructions FILE` reads the \
                  per-cycle CSV that tests/firmware_qemu.rs writes to firmware/target/instructions.csv)\n";
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cases_parse_and_print_back() {
        for s in SHIPPED_CASES {
            let c: Case = s.parse().unwrap();
            assert_eq!(c.label(), s);
        }
        let c: Case = "trap+rrt_star@3".parse().unwrap();
        assert_eq!(
            c,
            Case {
                scenario: "trap".into(),
                planner: Some(Planner::RrtStar),
                seed: Some(3)
            }
        );
        let c: Case = "dir/my+file.toml".parse().unwrap();
        assert_eq!((c.scenario.as_str(), c.planner), ("dir/my+file.toml", None));
        assert!("maze+astar".parse::<Case>().unwrap_err().contains("astar"));
        assert!("random@x".parse::<Case>().is_err());
        assert!("@3".parse::<Case>().is_err());
        assert_eq!(random_cases(2)[1].label(), "random@1");
    }

    fn cycle(index: usize, status: CycleStatus, iterations: u32, ns: u64) -> CycleCost {
        CycleCost {
            index,
            time: index as f64 * 0.05,
            status,
            source: if status.is_optimal() {
                CommandSource::Optimal
            } else {
                CommandSource::RelaxedGait
            },
            iterations,
            compute_ns: ns,
        }
    }

    #[test]
    fn stats_find_the_worst_cycles() {
        let run = |label: &str, cycles| CaseRun {
            case: Case::new(label),
            label: label.into(),
            seed: 0,
            max_iter: 64,
            max_iter_cycle: 2048,
            outcome: Outcome::GoalReached,
            cycles,
        };
        let a = run(
            "a",
            vec![
                cycle(0, CycleStatus::Optimal, 5, 1000),
                cycle(1, CycleStatus::Infeasible, 300, 9000),
            ],
        );
        let b = run(
            "b",
            vec![
                cycle(0, CycleStatus::Optimal, 12, 2000),
                cycle(1, CycleStatus::Optimal, 12, 300_000),
            ],
        );
        let st = cost_stats(&[&a, &b], 250_000);
        assert_eq!((st.runs, st.cycles, st.non_optimal), (2, 4, 1));
        assert_eq!(st.over_deadline, 1);
        let wo = st.worst_optimal.unwrap();
        assert_eq!((wo.value, wo.label.as_str(), wo.cycle), (12, "b", 0));
        assert_eq!(st.worst_all.unwrap().value, 300);
        assert_eq!(st.compute.max_ns, 300_000);
        let sl = st.slowest.unwrap();
        assert_eq!(
            (sl.compute_ns, sl.label.as_str(), sl.cycle, sl.iterations),
            (300_000, "b", 1, 12)
        );
        assert_eq!(sl.to_string(), "b cycle 1 (t = 0.05 s, optimal, 12 it)");
        let sa = cost_stats(&[&a], 250_000).slowest.unwrap();
        assert_eq!((sa.cycle, sa.status), (1, CycleStatus::Infeasible));
        assert!(cost_stats(&[], 250_000).slowest.is_none());
        assert_eq!((st.fallback, st.budget_exhausted), (0, 0));
    }

    #[test]
    fn instruction_files_are_read_and_checked() {
        let dir = std::env::temp_dir().join(format!("ldcbf-instr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("i.csv");
        std::fs::write(
            &p,
            format!("{INSTRUCTIONS_HEADER}\n0,optimal,4,40000\n1,infeasible,300,500000\n2,optimal,9,90000\n"),
        )
        .unwrap();
        let fw = read_instructions(&p).unwrap();
        assert_eq!((fw.cycles, fw.non_optimal), (3, 1));
        assert_eq!((fw.max_optimal, fw.max_all), (Some(90_000), 500_000));
        assert_eq!((fw.iterations_optimal, fw.iterations_all), (Some(9), 300));
        assert_eq!(
            (fw.max_all_cycle, fw.max_all_status.as_str()),
            (1, "infeasible")
        );
        std::fs::write(&p, format!("{INSTRUCTIONS_HEADER}\n0,optimal,4\n")).unwrap();
        let e = read_instructions(&p).unwrap_err().to_string();
        assert!(e.contains(":2:"), "{e}");
        std::fs::write(&p, "a,b\n").unwrap();
        assert!(read_instructions(&p).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
