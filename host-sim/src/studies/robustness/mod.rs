//! `ldcbf-sim robustness`: the closed loop under disturbances
//! ([`crate::plant::disturbance`]), with and without the LDCBF safety margin `delta`.
//!
//! A study runs every case (by default the deadline study's shipped cases,
//! [`crate::studies::deadline::SHIPPED_CASES`], and seeds `0..200` of the `random`
//! family) under every [`Condition`] (the undisturbed baseline, then each
//! disturbance at a moderate and a severe magnitude, [`default_conditions`]) and
//! every `delta` (m; `--set delta=...` for every case, replacing the files' own
//! margins; [`DEFAULT_DELTAS`]). Every run is simulated as `ldcbf-sim run`
//! would (own solver, 20 Hz, true clearance at 1 kHz) with a rayon pool; the
//! results do not depend on the number of threads.
//!
//! Per run it keeps the outcome and the true CoM clearance. A falling LIP is
//! stopped by the simulator only when its speed exceeds the controller's input
//! range (100 m/s, `Outcome::Diverged`), tens of metres later, so the study
//! declares the robot **fallen** at the first 1 kHz sample where the horizontal
//! CoM offset from the stance foot exceeds [`FALL_OFFSET_RATIO`] times the
//! plant's CoM height (a 27 degree lean, 1.7 times the largest offset of the
//! undisturbed walks: outside the LIP's validity), or on divergence; clearance
//! and collisions are counted up to the fall only (what the CoM crosses while
//! flying away says nothing about the barrier).
//!
//! Per cell (condition x delta x group, the groups being the shipped cases and
//! the random seeds): runs, success (goal reached, no collision, no fall),
//! collisions (some CoM sample inside a true obstacle before any fall), of them
//! in runs that never fell, falls, stuck, time limit, the minimum over all runs
//! of each run's minimum true CoM clearance before any fall (m), and the minimum
//! and 5th percentile (nearest rank) over the runs that never fell.
//!
//! Sharding, as for `batch`: `--shard i/n` runs the runs `k` (0-based, in
//! request order: condition, delta, shipped cases, random seeds) with
//! `k mod n == i - 1` and writes its own directory (`--out` is then required);
//! [`merge`] (`ldcbf-sim merge`) checks that the directories come from one
//! study and puts them together. The merged `runs.csv` is the unsharded
//! study's, byte for byte, and so is `table.md` but for its last line (runs,
//! jobs and wall time).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

mod error;
mod files;
#[cfg(test)]
mod tests;

pub use error::RobustnessError;
use files::write_dir;
pub use files::{RUNS_HEADER, is_robustness_dir, merge, read_dir, runs_csv};

use crate::report::{OutputDir, nearest_rank};
use crate::scenario::Scenario;
use crate::sim::{Outcome, SimOptions, SimResult, run};
use crate::studies::batch::Shard;
use crate::studies::deadline::{Case, random_cases, shipped_cases};

/// `Result` of this module.
type Result<T, E = RobustnessError> = core::result::Result<T, E>;

/// Fall threshold: horizontal CoM offset from the stance foot over the plant's
/// CoM height (0.5: 27 degrees of lean; the undisturbed walks of the shipped
/// scenarios stay below 0.3).
pub const FALL_OFFSET_RATIO: f64 = 0.5;

/// The margins of the default study, m: the paper's 0 and two positive ones.
pub const DEFAULT_DELTAS: [f64; 3] = [0.0, 0.05, 0.1];

/// One disturbance setting of a study.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Condition {
    /// Which disturbance (`none`, `push`, `height`, `foot`, `noise`).
    pub disturbance: String,
    /// Its magnitude in words and units, e.g. `0.1 m/s`.
    pub magnitude: String,
    /// The `--set` overrides that produce it (`disturbance.*` fields).
    pub sets: Vec<(String, String)>,
}

fn cond(disturbance: &str, magnitude: &str, sets: &[(&str, &str)]) -> Condition {
    Condition {
        disturbance: disturbance.into(),
        magnitude: magnitude.into(),
        sets: sets
            .iter()
            .map(|(k, v)| (format!("disturbance.{k}"), (*v).to_string()))
            .collect(),
    }
}

/// The default conditions (the choice of magnitudes is argued in
/// `docs/robustness.md`): no disturbance; a lateral push every 2 s from
/// t = 1.51 s (10 ms after a control cycle), alternating left and right, of
/// 0.1 and 0.3 m/s; a plant CoM 5 % and 10 % lower than the model's 1 m
/// (0.95 and 0.9 m); foot placement error sigma 5 mm and 2 cm per axis; state
/// estimation noise (sigma position / velocity / heading) 5 mm / 0.02 m/s /
/// 0.01 rad and 2 cm / 0.1 m/s / 0.03 rad.
pub fn default_conditions() -> Vec<Condition> {
    let push = |v: &'static str| {
        [
            ("push_time", "1.51"),
            ("push_period", "2.0"),
            ("push_alternate", "true"),
            ("push_lateral", v),
        ]
    };
    vec![
        cond("none", "-", &[]),
        cond("push", "0.1 m/s every 2 s", &push("0.1")),
        cond("push", "0.3 m/s every 2 s", &push("0.3")),
        cond(
            "height",
            "H = 0.95 m (-5 %)",
            &[("plant_com_height", "0.95")],
        ),
        cond(
            "height",
            "H = 0.90 m (-10 %)",
            &[("plant_com_height", "0.9")],
        ),
        cond("foot", "sigma 5 mm", &[("foot_sigma", "0.005")]),
        cond("foot", "sigma 2 cm", &[("foot_sigma", "0.02")]),
        cond(
            "noise",
            "5 mm, 0.02 m/s, 0.01 rad",
            &[
                ("noise_position", "0.005"),
                ("noise_velocity", "0.02"),
                ("noise_heading", "0.01"),
            ],
        ),
        cond(
            "noise",
            "2 cm, 0.1 m/s, 0.03 rad",
            &[
                ("noise_position", "0.02"),
                ("noise_velocity", "0.1"),
                ("noise_heading", "0.03"),
            ],
        ),
    ]
}

/// What `ldcbf-sim robustness` runs.
#[derive(Clone, Debug)]
pub struct RobustnessRequest {
    /// Shipped (or any) cases, the first group.
    pub cases: Vec<Case>,
    /// Seeds `0..random` of the `random` family, the second group.
    pub random: u64,
    /// Disturbance conditions.
    pub conditions: Vec<Condition>,
    /// Margins `delta`, m.
    pub deltas: Vec<f64>,
    /// Overrides for every run (`--set`), applied before the condition's and
    /// the delta.
    pub sets: Vec<(String, String)>,
    /// Worker threads (>= 1).
    pub jobs: usize,
    /// Progress bar on stderr.
    pub progress: bool,
    /// Directory for `runs.csv`, `table.md` and `summary.json` (none: nothing
    /// written; required for a shard).
    pub out: Option<PathBuf>,
    /// The part of the study to run ([`Shard::ALL`]: all of it).
    pub shard: Shard,
}

impl RobustnessRequest {
    /// The default study: shipped cases, 200 random seeds, the default
    /// conditions and margins, one job per core.
    pub fn new() -> Self {
        RobustnessRequest {
            cases: shipped_cases(),
            random: 200,
            conditions: default_conditions(),
            deltas: DEFAULT_DELTAS.to_vec(),
            sets: Vec::new(),
            jobs: std::thread::available_parallelism().map_or(1, |n| n.get()),
            progress: false,
            out: None,
            shard: Shard::ALL,
        }
    }
}

impl Default for RobustnessRequest {
    fn default() -> Self {
        Self::new()
    }
}

/// One run of a study.
#[derive(Clone, Debug, PartialEq)]
pub struct RobustRun {
    /// Index into the request's conditions.
    pub condition: usize,
    /// The margin, m.
    pub delta: f64,
    /// `shipped` or `random`.
    pub group: &'static str,
    /// The case label (`maze+rrt_star`, `random@17`).
    pub label: String,
    /// Why the simulation ended.
    pub outcome: Outcome,
    /// Time of the fall, s, if the robot fell (see the module docs).
    pub fall_time: Option<f64>,
    /// Goal reached and no collision.
    pub success: bool,
    /// The body touched a true obstacle before any fall (outcome `collided`).
    pub collision: bool,
    /// Minimum true body clearance (CoM clearance minus the body radius) before
    /// any fall, m (`+inf` without obstacles).
    pub min_clearance: f64,
    /// Footsteps landed.
    pub steps: usize,
    /// Cycles whose command is not the QP's optimum (relaxed or fallback).
    pub non_optimal_cycles: usize,
}

/// When the robot fell (first sample whose CoM is farther than
/// `FALL_OFFSET_RATIO * H` from its stance foot, or the end of a diverged run),
/// and the minimum clearance up to then.
pub fn fall_and_clearance(r: &SimResult, plant_com_height: f64) -> (Option<f64>, f64) {
    let limit = FALL_OFFSET_RATIO * plant_com_height;
    let mut k = 0usize;
    let mut min_c = f64::INFINITY;
    for s in &r.samples {
        while k + 1 < r.footsteps.len() && r.footsteps[k + 1].time <= s.time {
            k += 1;
        }
        let foot = r.footsteps[k].position;
        if (s.position - foot).norm() > limit {
            return (Some(s.time), min_c);
        }
        min_c = min_c.min(s.clearance);
    }
    let fall = (r.outcome == Outcome::Diverged).then(|| r.sim_time());
    (fall, min_c)
}

fn one_run(
    sc: &Scenario,
    condition: usize,
    delta: f64,
    group: &'static str,
    label: String,
) -> Result<RobustRun> {
    let opts = SimOptions {
        record_scans: false,
        ..SimOptions::default()
    };
    let r = run(sc, opts).map_err(|source| RobustnessError::Run {
        label: label.clone(),
        source,
    })?;
    let (fall_time, min_com) = fall_and_clearance(&r, r.disturbance.plant_com_height);
    let min_clearance = sc.robot.body_clearance(min_com);
    let collision =
        !sc.obstacles.is_empty() && min_clearance < -crate::world::robot::CONTACT_TOLERANCE;
    let reached = r.outcome == Outcome::GoalReached;
    Ok(RobustRun {
        condition,
        delta,
        group,
        label,
        outcome: r.outcome,
        fall_time,
        success: reached && !collision && fall_time.is_none(),
        collision,
        min_clearance,
        steps: r.steps(),
        non_optimal_cycles: r
            .cycles
            .iter()
            .filter(|c| !c.output.status.is_optimal())
            .count(),
    })
}

/// The statistics of one cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CellStats {
    /// Runs.
    pub runs: usize,
    /// Successful runs.
    pub success: usize,
    /// Runs with a collision before any fall.
    pub collisions: usize,
    /// Runs that never fell and had a collision.
    pub collisions_upright: usize,
    /// Runs that fell.
    pub falls: usize,
    /// Runs that ended stuck.
    pub stuck: usize,
    /// Runs that hit the time limit.
    pub time_limit: usize,
    /// Minimum over all runs of the minimum clearance before any fall, m.
    pub min_clearance: f64,
    /// Minimum over the runs that never fell of the minimum clearance, m (NaN
    /// if every run fell).
    pub min_clearance_upright: f64,
    /// 5th percentile (nearest rank) of the same, m.
    pub p5_clearance_upright: f64,
    /// Median of the same, m.
    pub median_clearance_upright: f64,
}

/// Statistics of a set of runs.
pub fn cell_stats(runs: &[&RobustRun]) -> CellStats {
    let min_all = runs
        .iter()
        .map(|r| r.min_clearance)
        .fold(f64::INFINITY, f64::min);
    let mut c: Vec<f64> = runs
        .iter()
        .filter(|r| r.fall_time.is_none())
        .map(|r| r.min_clearance)
        .collect();
    c.sort_by(f64::total_cmp);
    let rank = |p: f64| nearest_rank(&c, p).unwrap_or(f64::NAN);
    let count = |f: &dyn Fn(&RobustRun) -> bool| runs.iter().filter(|r| f(r)).count();
    CellStats {
        runs: runs.len(),
        success: count(&|r| r.success),
        collisions: count(&|r| r.collision),
        collisions_upright: count(&|r| r.collision && r.fall_time.is_none()),
        falls: count(&|r| r.fall_time.is_some()),
        stuck: count(&|r| r.fall_time.is_none() && r.outcome == Outcome::Stuck),
        time_limit: count(&|r| r.fall_time.is_none() && r.outcome == Outcome::TimeLimit),
        min_clearance: if runs.is_empty() { f64::NAN } else { min_all },
        min_clearance_upright: c.first().copied().unwrap_or(f64::NAN),
        p5_clearance_upright: rank(5.0),
        median_clearance_upright: rank(50.0),
    }
}

/// A finished study, or a shard of one, or shards merged.
#[derive(Clone, Debug)]
pub struct RobustnessReport {
    /// Labels of the shipped group's cases, as requested.
    pub cases: Vec<String>,
    /// Seeds `0..random` of the `random` family.
    pub random: u64,
    /// The conditions, as requested.
    pub conditions: Vec<Condition>,
    /// The margins, m.
    pub deltas: Vec<f64>,
    /// Every run of this shard, in request order (condition, delta, shipped
    /// cases, random seeds).
    pub runs: Vec<RobustRun>,
    /// Runs of the whole study (conditions x deltas x cases).
    pub study_runs: usize,
    /// Wall-clock time of the study, s (summed over the shards if merged).
    pub wall_time_s: f64,
    /// Worker threads (0 if merged).
    pub jobs: usize,
    /// The overrides applied to every run.
    pub sets: Vec<(String, String)>,
    /// The shard these runs are ([`Shard::ALL`] for a whole or merged study).
    pub shard: Shard,
    /// How many shards the study was split into (1 if it ran whole).
    pub shard_count: u32,
    /// Shards merged into this report (empty unless written by [`merge`]).
    pub merged_shards: Vec<u32>,
}

/// `summary.json` of a robustness directory: what the study is, and which
/// part of it the directory holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustnessMeta {
    /// Always [`KIND`] (how `merge` recognises the directory).
    pub kind: String,
    /// `ldcbf-sim` version that wrote it.
    pub version: String,
    /// Labels of the shipped group's cases.
    pub cases: Vec<String>,
    /// Seeds `0..random` of the `random` family.
    pub random: u64,
    /// The conditions.
    pub conditions: Vec<Condition>,
    /// The margins, m.
    pub deltas: Vec<f64>,
    /// The overrides applied to every run.
    pub sets: Vec<(String, String)>,
    /// Shard of this directory (`1/1` for a whole or merged study).
    pub shard: Shard,
    /// How many shards the study was split into (1 if it ran whole).
    pub shard_count: u32,
    /// Shards merged into this directory (empty unless written by `merge`).
    pub merged_shards: Vec<u32>,
    /// Worker threads (0 for a merged study).
    pub jobs: usize,
    /// Wall-clock time, s (sum over the shards for a merged study).
    pub wall_time_s: f64,
    /// Runs in this directory.
    pub runs: usize,
    /// Runs of the whole study.
    pub study_runs: usize,
}

/// `meta.kind` of a robustness directory's `summary.json`.
pub const KIND: &str = "ldcbf-sim robustness";

impl RobustnessMeta {
    fn of(rep: &RobustnessReport) -> Self {
        RobustnessMeta {
            kind: KIND.into(),
            version: env!("CARGO_PKG_VERSION").into(),
            cases: rep.cases.clone(),
            random: rep.random,
            conditions: rep.conditions.clone(),
            deltas: rep.deltas.clone(),
            sets: rep.sets.clone(),
            shard: rep.shard,
            shard_count: rep.shard_count,
            merged_shards: rep.merged_shards.clone(),
            jobs: rep.jobs,
            wall_time_s: rep.wall_time_s,
            runs: rep.runs.len(),
            study_runs: rep.study_runs,
        }
    }

    /// The fields two shards of one study must share.
    fn study_key(&self) -> String {
        format!(
            "{:?}",
            (
                &self.cases,
                self.random,
                &self.conditions,
                &self.deltas,
                &self.sets,
                self.shard_count
            )
        )
    }

    /// Labels of every case of the study (shipped, then random), with its group.
    fn all_cases(&self) -> Vec<(&'static str, String)> {
        let mut v: Vec<(&'static str, String)> =
            self.cases.iter().map(|c| ("shipped", c.clone())).collect();
        v.extend(
            random_cases(self.random)
                .iter()
                .map(|c| ("random", c.label())),
        );
        v
    }
}

/// Runs the study (all scenarios are loaded, and all errors reported, before
/// any simulation).
pub fn run_robustness(req: &RobustnessRequest) -> Result<RobustnessReport> {
    if req.jobs == 0 {
        return Err(RobustnessError::NoJobs);
    }
    if req.deltas.iter().any(|d| !(d.is_finite() && *d >= 0.0)) {
        return Err(RobustnessError::Delta);
    }
    if req.shard != Shard::ALL && req.out.is_none() {
        return Err(RobustnessError::ShardNeedsOut(req.shard));
    }
    if let Some(out) = &req.out {
        // Before the study, not after it: a bad --out fails at once.
        OutputDir::preflight(out).map_err(|source| RobustnessError::Out {
            path: out.clone(),
            source,
        })?;
    }
    let mut cases: Vec<(&'static str, Case)> =
        req.cases.iter().map(|c| ("shipped", c.clone())).collect();
    cases.extend(random_cases(req.random).into_iter().map(|c| ("random", c)));
    let study_runs = req.conditions.len() * req.deltas.len() * cases.len();
    let mut jobs = Vec::new();
    let mut k = 0u64;
    for (ci, cond) in req.conditions.iter().enumerate() {
        for &delta in &req.deltas {
            let mut sets = req.sets.clone();
            sets.extend(cond.sets.iter().cloned());
            sets.push(("delta".into(), format!("{delta}")));
            for (group, case) in &cases {
                k += 1;
                if !req.shard.holds(k - 1) {
                    continue;
                }
                let sc = case.load(&sets).map_err(|source| RobustnessError::Case {
                    disturbance: cond.disturbance.clone(),
                    magnitude: cond.magnitude.clone(),
                    delta,
                    source: Box::new(source),
                })?;
                jobs.push((ci, delta, *group, case.label(), sc));
            }
        }
    }
    if jobs.is_empty() && req.shard != Shard::ALL {
        return Err(RobustnessError::EmptyShard {
            shard: req.shard,
            runs: study_runs,
        });
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(req.jobs)
        .build()
        .map_err(RobustnessError::Threads)?;
    let bar = if req.progress {
        let b = indicatif::ProgressBar::new(jobs.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "robustness [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta}) {msg}",
            )
            .expect("valid template"),
        );
        b
    } else {
        indicatif::ProgressBar::hidden()
    };
    let failed = AtomicUsize::new(0);
    let t0 = Instant::now();
    let runs: Vec<Result<RobustRun>> = pool.install(|| {
        jobs.par_iter()
            .map(|(ci, delta, group, label, sc)| {
                let r = one_run(sc, *ci, *delta, group, label.clone());
                if r.as_ref().is_ok_and(|r| !r.success) {
                    let n = failed.fetch_add(1, Ordering::Relaxed) + 1;
                    bar.set_message(format!("{n} not successful"));
                }
                bar.inc(1);
                r
            })
            .collect()
    });
    bar.finish_and_clear();
    let runs: Vec<RobustRun> = runs.into_iter().collect::<Result<_>>()?;
    let rep = RobustnessReport {
        cases: req.cases.iter().map(Case::label).collect(),
        random: req.random,
        conditions: req.conditions.clone(),
        deltas: req.deltas.clone(),
        runs,
        study_runs,
        wall_time_s: t0.elapsed().as_secs_f64(),
        jobs: req.jobs,
        sets: req.sets.clone(),
        shard: req.shard,
        shard_count: req.shard.count,
        merged_shards: Vec::new(),
    };
    if let Some(out) = &req.out {
        write_dir(out, &rep)?;
    }
    Ok(rep)
}

/// The study as Markdown: one table per group, a row per condition and delta.
pub fn markdown(rep: &RobustnessReport) -> String {
    let mut s = String::new();
    let mm = |v: f64| {
        if v.is_finite() {
            format!("{:.0}", v * 1e3)
        } else {
            "n/a".into()
        }
    };
    for group in ["shipped", "random"] {
        let in_group: Vec<&RobustRun> = rep.runs.iter().filter(|r| r.group == group).collect();
        if in_group.is_empty() {
            continue;
        }
        let n = cell_stats(
            &in_group
                .iter()
                .copied()
                .filter(|r| r.condition == 0 && r.delta == rep.deltas[0])
                .collect::<Vec<_>>(),
        )
        .runs;
        let per_row = if rep.runs.len() == rep.study_runs {
            format!("{n} runs per row")
        } else {
            "part of the study: the runs per row are the success column's".into()
        };
        let _ = writeln!(
            s,
            "\n{} ({per_row})\n",
            if group == "shipped" {
                "Shipped cases"
            } else {
                "Random environments"
            }
        );
        s += "| disturbance | magnitude | delta [m] | success | fell | collision (upright) | stuck / time limit | min clearance before fall [mm] | upright: min / p5 / median [mm] |\n";
        s += "|---|---|---|---|---|---|---|---|---|\n";
        for (ci, c) in rep.conditions.iter().enumerate() {
            for &d in &rep.deltas {
                let cell: Vec<&RobustRun> = in_group
                    .iter()
                    .copied()
                    .filter(|r| r.condition == ci && r.delta == d)
                    .collect();
                let st = cell_stats(&cell);
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {}/{} | {} | {} ({}) | {} / {} | {} | {} / {} / {} |",
                    c.disturbance,
                    c.magnitude,
                    d,
                    st.success,
                    st.runs,
                    st.falls,
                    st.collisions,
                    st.collisions_upright,
                    st.stuck,
                    st.time_limit,
                    mm(st.min_clearance),
                    mm(st.min_clearance_upright),
                    mm(st.p5_clearance_upright),
                    mm(st.median_clearance_upright)
                );
            }
        }
    }
    let extra: Vec<String> = rep.sets.iter().map(|(k, v)| format!("{k}={v}")).collect();
    // Unsharded: `N runs, J jobs, wall time T s` (as before sharding existed).
    let (part, jobs, summed) = if !rep.merged_shards.is_empty() {
        let shards: Vec<String> = rep.merged_shards.iter().map(u32::to_string).collect();
        (
            format!(
                " of {} (merged shards {} of {})",
                rep.study_runs,
                shards.join(", "),
                rep.shard_count
            ),
            String::new(),
            " summed over the shards",
        )
    } else if rep.shard != Shard::ALL {
        (
            format!(" of {} (shard {})", rep.study_runs, rep.shard),
            format!(", {} jobs", rep.jobs),
            "",
        )
    } else {
        (String::new(), format!(", {} jobs", rep.jobs), "")
    };
    let _ = writeln!(
        s,
        "\n{} runs{part}{jobs}, wall time {:.1} s{summed}{}",
        rep.runs.len(),
        rep.wall_time_s,
        if extra.is_empty() {
            String::new()
        } else {
            format!("; every run with {}", extra.join(", "))
        }
    );
    s
}
