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
//! (measured by the simulator around `Controller::step` only). With
//! `--repeat K` ([`DeadlineRequest::repeat`], [`SimOptions::timing_repeats`])
//! each cycle's call is timed `K` times on the same input and the same
//! controller state (clones made just before the call) and its time is the
//! minimum: the cycle's compute without the scheduler's noise. The closed loops,
//! hence the cycles, statuses and iterations, are the same for every `K`.
//!
//! Two kinds of cost, reported side by side by [`markdown`]:
//!
//! * **Deterministic**: the iteration counts. They do not depend on the machine
//!   or its load, so CI can assert them (`host-sim/tests/deadline_iterations.rs`)
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

use ldcbf_controller::{CommandSource, CycleStatus};
use rayon::prelude::*;

mod markdown;
mod stats;
#[cfg(test)]
mod tests;

pub use markdown::markdown;
pub use stats::{
    CostStats, FirmwareInstructions, InstructionsError, Slowest, Worst, cost_stats,
    read_instructions,
};

use crate::plan::Planner;
use crate::report::{ComputeStats, compute_stats};
use crate::scenario::{LoadOptions, Scenario, ScenarioError, load};
use crate::sim::{Outcome, SimError, SimOptions, run};

/// Default deadline per control cycle, µs: the 100,000 instructions at
/// 400 MHz.
pub const DEFAULT_DEADLINE_US: f64 = 250.0;

/// Why a deadline study (or one of its cases) could not run: a bad argument,
/// a case whose scenario does not load or whose run fails (naming the case), or
/// an unreadable instruction file.
#[derive(Debug, thiserror::Error)]
pub enum DeadlineError {
    /// `--jobs 0`.
    #[error("--jobs must be >= 1")]
    NoJobs,
    /// `--repeat 0`.
    #[error("--repeat must be >= 1 (timings of each control cycle), got 0")]
    NoRepeat,
    /// `--repeat` above [`MAX_TIMING_REPEATS`](crate::sim::MAX_TIMING_REPEATS).
    #[error("--repeat must be at most {max} (timings of each control cycle), got {0}", max = crate::sim::MAX_TIMING_REPEATS)]
    TooManyRepeats(u32),
    /// `--deadline-us` is not a positive number (µs).
    #[error("--deadline-us must be a positive number of microseconds, got {0}")]
    Deadline(f64),
    /// `--clock-mhz` is not a positive number (MHz).
    #[error("--clock-mhz must be a positive number, got {0}")]
    Clock(f64),
    /// Neither scenarios nor `--random N` were given.
    #[error("nothing to run: give scenarios or --random N")]
    NothingToRun,
    /// The case's scenario could not be loaded or validated.
    #[error("case {label}")]
    Load {
        /// The case ([`Case::label`]).
        label: String,
        /// Why.
        source: ScenarioError,
    },
    /// The case's simulation could not start or was cancelled.
    #[error("case {label}")]
    Run {
        /// The case ([`Case::label`]).
        label: String,
        /// Why.
        source: SimError,
    },
    /// The worker thread pool could not be built.
    #[error("cannot start the worker threads")]
    Threads(#[source] rayon::ThreadPoolBuildError),
    /// The per-cycle instruction CSV could not be read.
    #[error(transparent)]
    Instructions(#[from] InstructionsError),
}

/// Default clock of the target processor, MHz, used to turn instruction counts
/// into time (one instruction per clock).
pub const DEFAULT_CLOCK_MHZ: f64 = 400.0;

/// The shipped closed loops a deadline study runs by default (and the CI
/// check): every shipped scenario except the seeded families (`random`, which
/// is `--random N`, and `corridor`, `doorway`, `cup`, `wall-start`, `clutter`,
/// `thin`, which `batch` and `host-sim/tests/sim_body.rs` run, and the people families
/// `crossing`, `headon`, `crowd`, `room-crossing`, which `host-sim/tests/sim_people.rs`
/// runs), `maze` and `trap` both without and with RRT* subgoals
/// (`maze` ships with them, `maze+none` is the MPC alone),
/// `crowded` with its seed 0, the LiDAR regressions `cup-mouth` and
/// `corner-start`, and the unknown-map regressions `occluded`, `needle`,
/// `cup-arm` and `cup-front` (LiDAR, the map and planning on it).
pub const SHIPPED_CASES: [&str; 14] = [
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
    "occluded",
    "needle",
    "cup-arm",
    "cup-front",
];

/// The large maps a deadline study runs by default besides [`SHIPPED_CASES`]
/// (kept out of them, which the iteration and budget tests run in debug
/// builds): `large-map`, 10,000 polygons, whose cycles cost what a small map's
/// do because the controller is handed only the map index's candidates
/// ([`crate::world::obstacle_index`]; `host-sim/tests/obstacle_index.rs` runs it).
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
    pub fn load(&self, sets: &[(String, String)]) -> Result<Scenario, DeadlineError> {
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
        .map_err(|source| DeadlineError::Load {
            label: self.label(),
            source,
        })
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
pub fn run_cases(
    cases: &[Case],
    sets: &[(String, String)],
    jobs: usize,
) -> Result<Vec<CaseRun>, DeadlineError> {
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
) -> Result<Vec<CaseRun>, DeadlineError> {
    if jobs == 0 {
        return Err(DeadlineError::NoJobs);
    }
    if repeat == 0 {
        return Err(DeadlineError::NoRepeat);
    }
    if repeat > crate::sim::MAX_TIMING_REPEATS {
        return Err(DeadlineError::TooManyRepeats(repeat));
    }
    let scenarios: Vec<Scenario> = cases
        .iter()
        .map(|c| c.load(sets))
        .collect::<Result<_, _>>()?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(DeadlineError::Threads)?;
    // No clearances: the study does not report them, and the walk is the same.
    let opts = SimOptions {
        record_scans: false,
        record_clearance: false,
        timing_repeats: repeat,
        ..SimOptions::default()
    };
    let runs: Vec<Result<CaseRun, DeadlineError>> = pool.install(|| {
        cases
            .par_iter()
            .zip(scenarios.par_iter())
            .map(|(case, sc)| {
                let r = run(sc, opts).map_err(|source| DeadlineError::Run {
                    label: case.label(),
                    source,
                })?;
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
pub fn run_deadline(req: &DeadlineRequest) -> Result<DeadlineReport, DeadlineError> {
    if !(req.deadline_us.is_finite() && req.deadline_us > 0.0) {
        return Err(DeadlineError::Deadline(req.deadline_us));
    }
    if !(req.clock_mhz.is_finite() && req.clock_mhz > 0.0) {
        return Err(DeadlineError::Clock(req.clock_mhz));
    }
    if req.repeat == 0 {
        return Err(DeadlineError::NoRepeat);
    }
    if req.repeat > crate::sim::MAX_TIMING_REPEATS {
        return Err(DeadlineError::TooManyRepeats(req.repeat));
    }
    if req.cases.is_empty() && req.random == 0 {
        return Err(DeadlineError::NothingToRun);
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
