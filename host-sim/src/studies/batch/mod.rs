//! Batch evaluation: many seeds of a scenario family, in parallel, sharded
//! across machines, and merged.
//!
//! * [`run_batch`] (`ldcbf-sim batch`): loads the family's scenario file once per
//!   seed exactly as `ldcbf-sim run <family> --seed S` does (same generator, same
//!   overrides: `--planner`, `--perception` and `--set` become `--set`
//!   overrides), simulates every seed of the shard with a rayon pool of `jobs`
//!   threads (no figures, no scans kept), and writes an output directory
//!   atomically (temporary sibling, renamed at the end; see
//!   [`crate::report::OutputDir`]):
//!   * `runs.csv`: one [`RunRow`] per seed, sorted by seed;
//!   * `summary.json`: the [`BatchMeta`] (what ran, shard, wall time) and the
//!     [`Aggregate`];
//!   * `summary.md`: the aggregate as a Markdown table ([`markdown_table`]).
//! * Sharding: `--shard i/n` (1-based) runs the seeds `s` of the range with
//!   `(s - start) mod n == i - 1`, so shards are interleaved and balanced; every
//!   shard writes its own directory.
//! * [`merge`] (`ldcbf-sim merge`): checks that the shard directories come from
//!   the same study (family, seed range, planner, perception, overrides,
//!   solver, rate, shard count), that no shard or seed appears twice and, unless
//!   partial results are allowed, that every seed of the range is there; then
//!   writes the same three files for the whole study.
//!
//! Aggregates: success = goal reached with no CoM sample inside a TRUE obstacle
//! (docs/maths.md §4); steps and time to goal are over the successful runs; compute times
//! are per-run statistics (the p99 of each run's controller calls), summarised by
//! their median and maximum over runs (the raw call times are not kept, so a
//! merged study can still be summarised). Timings from different machines are
//! comparable only as far as the machines are.

use crate::studies::output::write_files;
use crate::studies::shards::{merged_shards, missing_shards};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::report::{OutputDir, Summary, summarize};
mod aggregate;
mod error;
mod seeds;
#[cfg(test)]
mod tests;

pub use aggregate::{Aggregate, aggregate, label, markdown_table};
pub use error::BatchError;
pub use seeds::{JOBS_PER_CORE, MAX_SEEDS, SeedRange, Shard, cap_jobs};

use crate::plan::Planner;
use crate::scenario::{LoadOptions, limits, load};
use crate::sense::Perception;
use crate::sim::{MpcRate, SimOptions, Solver, run};

/// `Result` of this module.
type Result<T, E = BatchError> = core::result::Result<T, E>;

/// What `ldcbf-sim batch` needs.
#[derive(Clone, Debug)]
pub struct BatchRequest {
    /// Scenario family: a scenario name or path whose file has a `[generator]`.
    pub family: String,
    /// Seeds of the whole study.
    pub seeds: SeedRange,
    /// Planner override (`None` = the file's).
    pub planner: Option<Planner>,
    /// Perception override (`None` = the file's).
    pub perception: Option<Perception>,
    /// Further `--set key=value` overrides, as for `run`.
    pub sets: Vec<(String, String)>,
    /// Worker threads (>= 1).
    pub jobs: usize,
    /// This machine's part of the study.
    pub shard: Shard,
    /// Output directory (default [`BatchRequest::default_out`]).
    pub out: Option<PathBuf>,
    /// Show a progress bar on stderr (hidden anyway when stderr is no terminal).
    pub progress: bool,
    /// QP solver.
    pub solver: Solver,
    /// Controller rate.
    pub mpc_rate: MpcRate,
}

impl BatchRequest {
    /// A request with the defaults of the CLI: the family's own planner and
    /// perception, one job per core, the whole range, no progress bar.
    pub fn new(family: &str, seeds: SeedRange) -> Self {
        BatchRequest {
            family: family.into(),
            seeds,
            planner: None,
            perception: None,
            sets: Vec::new(),
            jobs: std::thread::available_parallelism().map_or(1, |n| n.get()),
            shard: Shard::ALL,
            out: None,
            progress: false,
            solver: Solver::Own,
            mpc_rate: MpcRate::Hz(20),
        }
    }

    /// `out/batch-<family>-<planner>-<perception>[-shard<I>of<N>]`.
    pub fn default_out(&self, family: &str, planner: Planner, perception: Perception) -> PathBuf {
        let mut name = format!("batch-{family}-{}-{}", planner.name(), perception.name());
        if self.shard.count > 1 {
            name += &format!("-shard{}of{}", self.shard.index, self.shard.count);
        }
        PathBuf::from("out").join(name)
    }

    /// All overrides in the order they are applied: planner, perception, sets.
    fn all_sets(&self) -> Vec<(String, String)> {
        let mut v = Vec::new();
        if let Some(p) = self.planner {
            v.push(("planner".into(), format!("\"{}\"", p.name())));
        }
        if let Some(p) = self.perception {
            v.push(("perception".into(), format!("\"{}\"", p.name())));
        }
        v.extend(self.sets.iter().cloned());
        v
    }
}

/// One run of a batch: a row of `runs.csv`. Units: m, s, ns, ms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRow {
    /// Seed.
    pub seed: u64,
    /// Why the run ended: `goal_reached`, `time_limit`, `stuck` or `diverged`
    /// (the summary's `ended`; a run whose body touched an obstacle has
    /// `collision` set whatever its end).
    pub outcome: String,
    /// Goal reached, the body never touched a true obstacle, no foot on one.
    pub success: bool,
    /// The body touched a true obstacle (the summary's outcome `collided`).
    pub collision: bool,
    /// Footsteps landed.
    pub steps: u64,
    /// Simulated time at the end, s.
    pub sim_time: f64,
    /// Final distance to the goal, m.
    pub final_distance: f64,
    /// Minimum CoM clearance to the true obstacles over the 1 kHz samples, m.
    pub min_com_clearance: f64,
    /// Minimum footstep clearance, m.
    pub min_footstep_clearance: f64,
    /// Largest violation of a cycle's own rows by its applied plan.
    pub max_violation: f64,
    /// Control cycles.
    pub cycles: u64,
    /// Cycles whose status was not optimal.
    pub non_optimal_cycles: u64,
    /// Median controller call, ns.
    pub compute_p50_ns: u64,
    /// 99th percentile of the controller calls, ns.
    pub compute_p99_ns: u64,
    /// Slowest controller call, ns.
    pub compute_max_ns: u64,
    /// The planner failed (the run walked to the goal directly).
    pub planner_failed: bool,
    /// Subgoals (1 = the goal only).
    pub subgoals: u64,
    /// Planning time, ms (0 without a planner).
    pub plan_time_ms: f64,
    /// Mean obstacles handed to the controller per cycle.
    pub obstacles_seen_mean: f64,
    /// Wall-clock time of the whole run (simulation and summary), ms.
    pub wall_ms: f64,
    /// Some footprint overlapped a true obstacle.
    pub foot_collision: bool,
    /// Minimum body clearance (CoM clearance minus the body radius), m.
    pub min_body_clearance: f64,
    /// Contacts where the robot moved into an obstacle (the summary's
    /// `contacts_robot`).
    pub contacts_robot: u64,
    /// Contacts where a person moved into the standing robot (the summary's
    /// `contacts_person`).
    pub contacts_person: u64,
    /// Plans on the perceived map after the first (0 without LiDAR mapping).
    pub replans: u64,
    /// Plans on the perceived map that found no path.
    pub plan_failures: u64,
    /// Median wall-clock time of a map update, ms (0 without mapping).
    pub map_update_p50_ms: f64,
    /// Largest wall-clock time of a map update, ms.
    pub map_update_max_ms: f64,
    /// Median wall-clock time of a plan on the perceived map, ms.
    pub plan_p50_ms: f64,
    /// Largest wall-clock time of a plan on the perceived map, ms.
    pub plan_max_ms: f64,
}

const CSV_HEADER: &str = "seed,outcome,success,collision,steps,sim_time,final_distance,\
min_com_clearance,min_footstep_clearance,max_violation,cycles,non_optimal_cycles,\
compute_p50_ns,compute_p99_ns,compute_max_ns,planner_failed,subgoals,plan_time_ms,\
obstacles_seen_mean,wall_ms,foot_collision,min_body_clearance,contacts_robot,contacts_person,\
replans,plan_failures,map_update_p50_ms,map_update_max_ms,plan_p50_ms,plan_max_ms";

impl RunRow {
    fn csv(&self) -> String {
        format!(
            "{},{},{},{},{},{},{},{},{},{:e},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            self.seed,
            self.outcome,
            u8::from(self.success),
            u8::from(self.collision),
            self.steps,
            self.sim_time,
            self.final_distance,
            self.min_com_clearance,
            self.min_footstep_clearance,
            self.max_violation,
            self.cycles,
            self.non_optimal_cycles,
            self.compute_p50_ns,
            self.compute_p99_ns,
            self.compute_max_ns,
            u8::from(self.planner_failed),
            self.subgoals,
            self.plan_time_ms,
            self.obstacles_seen_mean,
            self.wall_ms,
            u8::from(self.foot_collision),
            self.min_body_clearance,
            self.contacts_robot,
            self.contacts_person,
            self.replans,
            self.plan_failures,
            self.map_update_p50_ms,
            self.map_update_max_ms,
            self.plan_p50_ms,
            self.plan_max_ms
        )
    }

    /// Checks a row read from the `runs.csv` of a directory of `meta`: its
    /// seed lies in the study's range and in the directory's shard (for a
    /// merge, in the range), and it claims success only as a run can: the
    /// goal reached, no contact the robot caused, and a collision only when a
    /// person caused a contact.
    fn check(&self, meta: &BatchMeta) -> Result<(), String> {
        let range = meta.seeds;
        if !(range.start..range.end).contains(&self.seed) {
            return Err(format!(
                "seed {} is outside the study's seeds {range}",
                self.seed
            ));
        }
        if meta.merged_shards.is_empty() && !meta.shard.holds(self.seed - range.start) {
            return Err(format!(
                "seed {} is not in shard {} of seeds {range}",
                self.seed, meta.shard
            ));
        }
        if self.success
            && (self.outcome != "goal_reached"
                || self.contacts_robot > 0
                || self.collision && self.contacts_person == 0)
        {
            return Err(format!(
                "seed {}: success with outcome {:?}, collision {}, {} contacts caused by the \
                 robot and {} by people (a success reaches the goal, and any collision is a \
                 person's)",
                self.seed,
                self.outcome,
                u8::from(self.collision),
                self.contacts_robot,
                self.contacts_person
            ));
        }
        Ok(())
    }

    fn parse(line: &str) -> Result<Self, String> {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != CSV_HEADER.split(',').count() {
            return Err(format!(
                "expected {} fields, got {}",
                CSV_HEADER.split(',').count(),
                f.len()
            ));
        }
        fn p<T: core::str::FromStr>(s: &str, name: &str) -> Result<T, String> {
            s.trim().parse().map_err(|_| format!("bad {name} {s:?}"))
        }
        let b = |s: &str, name: &str| match s.trim() {
            "1" => Ok(true),
            "0" => Ok(false),
            _ => Err(format!("bad {name} {s:?}")),
        };
        Ok(RunRow {
            seed: p(f[0], "seed")?,
            outcome: f[1].trim().to_string(),
            success: b(f[2], "success")?,
            collision: b(f[3], "collision")?,
            steps: p(f[4], "steps")?,
            sim_time: p(f[5], "sim_time")?,
            final_distance: p(f[6], "final_distance")?,
            min_com_clearance: p(f[7], "min_com_clearance")?,
            min_footstep_clearance: p(f[8], "min_footstep_clearance")?,
            max_violation: p(f[9], "max_violation")?,
            cycles: p(f[10], "cycles")?,
            non_optimal_cycles: p(f[11], "non_optimal_cycles")?,
            compute_p50_ns: p(f[12], "compute_p50_ns")?,
            compute_p99_ns: p(f[13], "compute_p99_ns")?,
            compute_max_ns: p(f[14], "compute_max_ns")?,
            planner_failed: b(f[15], "planner_failed")?,
            subgoals: p(f[16], "subgoals")?,
            plan_time_ms: p(f[17], "plan_time_ms")?,
            obstacles_seen_mean: p(f[18], "obstacles_seen_mean")?,
            wall_ms: p(f[19], "wall_ms")?,
            foot_collision: b(f[20], "foot_collision")?,
            min_body_clearance: p(f[21], "min_body_clearance")?,
            contacts_robot: p(f[22], "contacts_robot")?,
            contacts_person: p(f[23], "contacts_person")?,
            replans: p(f[24], "replans")?,
            plan_failures: p(f[25], "plan_failures")?,
            map_update_p50_ms: p(f[26], "map_update_p50_ms")?,
            map_update_max_ms: p(f[27], "map_update_max_ms")?,
            plan_p50_ms: p(f[28], "plan_p50_ms")?,
            plan_max_ms: p(f[29], "plan_max_ms")?,
        })
    }
}

/// What a batch directory is: the study and this part of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BatchMeta {
    /// Always `"ldcbf-sim batch"` (how `merge` recognises the directory).
    pub kind: String,
    /// `ldcbf-sim` version that wrote it.
    pub version: String,
    /// Family as given (`random`, a path, ...).
    pub family: String,
    /// Scenario name of the family.
    pub scenario: String,
    /// Seeds of the whole study.
    pub seeds: SeedRange,
    /// Shard of this directory (`1/1` for a whole or merged study).
    pub shard: Shard,
    /// Shards merged into this directory (empty unless written by `merge`).
    pub merged_shards: Vec<u32>,
    /// Planner used.
    pub planner: String,
    /// Perception used.
    pub perception: String,
    /// Every override applied (`--planner`, `--perception`, `--set`), in order.
    pub sets: Vec<(String, String)>,
    /// QP solver.
    pub solver: String,
    /// Controller rate.
    pub mpc_rate: String,
    /// Worker threads (0 for a merged study).
    pub jobs: usize,
    /// Wall-clock time of the batch, s (sum over shards for a merged study).
    pub wall_time_s: f64,
    /// Runs in this directory.
    pub runs: usize,
}

impl BatchMeta {
    /// The fields two shards of one study must share.
    fn study_key(
        &self,
    ) -> (
        String,
        SeedRange,
        String,
        String,
        String,
        String,
        String,
        u32,
    ) {
        (
            self.scenario.clone(),
            self.seeds,
            self.planner.clone(),
            self.perception.clone(),
            format!("{:?}", self.sets),
            self.solver.clone(),
            self.mpc_rate.clone(),
            self.shard.count,
        )
    }
}

/// What a finished batch or merge produced.
#[derive(Debug)]
pub struct BatchReport {
    /// The directory written.
    pub out_dir: PathBuf,
    /// What ran.
    pub meta: BatchMeta,
    /// The runs, by seed.
    pub rows: Vec<RunRow>,
    /// Their aggregate.
    pub aggregate: Aggregate,
}

#[derive(Serialize, Deserialize)]
struct SummaryFile {
    meta: BatchMeta,
    aggregate: Aggregate,
}

fn write_dir(out: &Path, meta: &BatchMeta, rows: &[RunRow], agg: &Aggregate) -> Result<PathBuf> {
    let mut csv = String::from(CSV_HEADER);
    csv.push('\n');
    for r in rows {
        csv += &r.csv();
        csv.push('\n');
    }
    let json = serde_json::to_string_pretty(&SummaryFile {
        meta: meta.clone(),
        aggregate: agg.clone(),
    })?;
    let mut md = format!(
        "# {} seeds {} (shard {}), {} runs\n\nplanner {}, perception {}, overrides {:?}; wall time {:.1} s\n\n",
        meta.scenario,
        meta.seeds,
        meta.shard,
        meta.runs,
        meta.planner,
        meta.perception,
        meta.sets,
        meta.wall_time_s
    );
    md += &markdown_table(&[(label(meta), agg.clone())]);
    let files = [
        ("runs.csv", csv),
        ("summary.json", json + "\n"),
        ("summary.md", md),
    ];
    Ok(write_files(out, &files)?)
}

/// Runs a batch (see the module docs). Nothing is written unless every run
/// completed.
pub fn run_batch(req: &BatchRequest) -> Result<BatchReport> {
    if req.jobs == 0 {
        return Err(BatchError::NoJobs);
    }
    if req.seeds.len() > MAX_SEEDS {
        return Err(BatchError::TooManySeeds(req.seeds));
    }
    let jobs = cap_jobs(req.jobs).0;
    let sets = req.all_sets();
    let first = load(
        &req.family,
        &LoadOptions {
            seed: Some(req.seeds.start),
            sets: sets.clone(),
        },
    )?;
    if first.generator.is_none() {
        return Err(BatchError::NoGenerator {
            name: first.name.clone(),
            file: first.source.clone(),
        });
    }
    let seeds = req.shard.seeds(req.seeds);
    if seeds.is_empty() {
        return Err(BatchError::EmptyShard {
            shard: req.shard,
            seeds: req.seeds,
        });
    }
    let out = req
        .out
        .clone()
        .unwrap_or_else(|| req.default_out(&first.name, first.planner, first.perception));
    OutputDir::preflight(&out).map_err(|source| BatchError::Out {
        path: out.clone(),
        source,
    })?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(BatchError::Threads)?;
    let bar = progress_bar(
        req.progress,
        seeds.len(),
        &format!("{} {}", first.name, req.shard),
    );
    let failures = AtomicUsize::new(0);
    let opts = SimOptions {
        solver: req.solver,
        mpc_rate: req.mpc_rate,
        record_scans: false,
        record_qps: false,
        record_clearance: true,
        timing_repeats: 1,
    };
    let t0 = Instant::now();
    let rows: Vec<Result<RunRow>> = pool.install(|| {
        seeds
            .par_iter()
            .map(|&seed| {
                let t = Instant::now();
                let sc = load(
                    &req.family,
                    &LoadOptions {
                        seed: Some(seed),
                        sets: sets.clone(),
                    },
                )
                .map_err(|source| BatchError::SeedScenario { seed, source })?;
                let r = run(&sc, opts).map_err(|source| BatchError::SeedRun { seed, source })?;
                let row = run_row(seed, &summarize(&r), t);
                if !row.success {
                    let n = failures.fetch_add(1, Ordering::Relaxed) + 1;
                    bar.set_message(format!("{n} not successful"));
                }
                bar.inc(1);
                Ok(row)
            })
            .collect()
    });
    bar.finish_and_clear();
    let wall = t0.elapsed().as_secs_f64();
    let rows: Vec<RunRow> = rows.into_iter().collect::<Result<_>>()?;
    let meta = BatchMeta {
        kind: "ldcbf-sim batch".into(),
        version: env!("CARGO_PKG_VERSION").into(),
        family: req.family.clone(),
        scenario: first.name.clone(),
        seeds: req.seeds,
        shard: req.shard,
        merged_shards: Vec::new(),
        planner: first.planner.name().into(),
        perception: first.perception.name().into(),
        sets,
        solver: match req.solver {
            Solver::Own => "own".into(),
            Solver::Clarabel => "clarabel".into(),
        },
        mpc_rate: req.mpc_rate.to_string(),
        jobs,
        wall_time_s: wall,
        runs: rows.len(),
    };
    let agg = aggregate(&rows);
    let out_dir = write_dir(&out, &meta, &rows, &agg)?;
    Ok(BatchReport {
        out_dir,
        meta,
        rows,
        aggregate: agg,
    })
}

/// The batch row of the run of `seed` from its summary; `started` is when
/// the run began (its wall time ends now).
fn run_row(seed: u64, s: &Summary, started: Instant) -> RunRow {
    RunRow {
        seed,
        outcome: s.ended.clone(),
        success: s.success,
        collision: s.collision,
        steps: s.steps as u64,
        sim_time: s.sim_time,
        final_distance: s.final_distance,
        min_com_clearance: s.min_com_clearance.unwrap_or(f64::INFINITY),
        min_footstep_clearance: s.min_footstep_clearance.unwrap_or(f64::INFINITY),
        max_violation: s.max_violation,
        cycles: s.cycles as u64,
        non_optimal_cycles: (s.cycles - s.status_counts.get("optimal").copied().unwrap_or(0))
            as u64,
        compute_p50_ns: s.compute.p50_ns,
        compute_p99_ns: s.compute.p99_ns,
        compute_max_ns: s.compute.max_ns,
        planner_failed: s.planner_error.is_some(),
        subgoals: s.subgoals as u64,
        plan_time_ms: s.plan_time_ms.unwrap_or(0.0),
        obstacles_seen_mean: s.obstacles_seen_mean,
        wall_ms: started.elapsed().as_secs_f64() * 1e3,
        foot_collision: s.foot_collision,
        min_body_clearance: s.min_body_clearance.unwrap_or(f64::INFINITY),
        contacts_robot: s.contacts_robot as u64,
        contacts_person: s.contacts_person as u64,
        replans: s.mapping.as_ref().map_or(0, |m| m.replans as u64),
        plan_failures: s.mapping.as_ref().map_or(0, |m| m.plan_failures as u64),
        map_update_p50_ms: s.mapping.as_ref().map_or(0.0, |m| m.map_update_p50_ms),
        map_update_max_ms: s.mapping.as_ref().map_or(0.0, |m| m.map_update_max_ms),
        plan_p50_ms: s.mapping.as_ref().map_or(0.0, |m| m.plan_time_p50_ms),
        plan_max_ms: s.mapping.as_ref().map_or(0.0, |m| m.plan_time_max_ms),
    }
}

/// The batch's progress bar over `len` runs (hidden unless `show`).
fn progress_bar(show: bool, len: usize, prefix: &str) -> indicatif::ProgressBar {
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let b = indicatif::ProgressBar::new(len as u64);
    b.set_style(
        indicatif::ProgressStyle::with_template(
            "{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta}) {msg}",
        )
        .expect("valid template"),
    );
    b.set_prefix(prefix.to_string());
    b
}

/// Reads a batch directory written by [`run_batch`] or [`merge`]. Errors name
/// the directory or file (and line) and say what is wrong: not a directory, no
/// `summary.json`, not a batch summary (another schema, a truncated or binary
/// file), a `runs.csv` with a foreign header, a malformed or truncated row.
pub fn read_dir(dir: &Path) -> Result<(BatchMeta, Aggregate, Vec<RunRow>)> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(BatchError::NotADirectory {
                dir: dir.to_path_buf(),
            });
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(BatchError::NoDirectory {
                dir: dir.to_path_buf(),
            });
        }
        Err(error) => {
            return Err(BatchError::Metadata {
                dir: dir.to_path_buf(),
                error,
            });
        }
    }
    let read = |name: &str| -> Result<(PathBuf, String)> {
        let p = dir.join(name);
        if !p.exists() {
            return Err(BatchError::Missing {
                dir: dir.to_path_buf(),
                name: name.to_string(),
            });
        }
        let max = if name == "runs.csv" {
            limits::MAX_TABLE_BYTES
        } else {
            limits::MAX_FILE_BYTES
        };
        let bytes = match limits::read_regular_file(&p, max) {
            Ok(b) => b,
            Err(error) => return Err(BatchError::Read { path: p, error }),
        };
        let Ok(text) = String::from_utf8(bytes) else {
            return Err(BatchError::NotText { path: p });
        };
        if text.trim().is_empty() {
            return Err(BatchError::Empty { path: p });
        }
        Ok((p, text))
    };
    let (sj, text) = read("summary.json")?;
    let sf: SummaryFile = match serde_json::from_str(&text) {
        Ok(sf) => sf,
        Err(error) => return Err(BatchError::Summary { path: sj, error }),
    };
    if sf.meta.kind != "ldcbf-sim batch" {
        return Err(BatchError::Kind {
            path: sj,
            kind: sf.meta.kind,
        });
    }
    let (csv, text) = read("runs.csv")?;
    let mut lines = text.lines();
    if lines.next() != Some(CSV_HEADER) {
        return Err(BatchError::Header { path: csv });
    }
    if !text.ends_with('\n') {
        return Err(BatchError::Truncated {
            path: csv,
            line: text.lines().count(),
        });
    }
    let meta = &sf.meta;
    if !meta.merged_shards.is_empty() && meta.shard != Shard::ALL || meta.merged_shards.contains(&0)
    {
        return Err(BatchError::Shards {
            path: sj,
            shard: meta.shard,
            merged: meta.merged_shards.clone(),
        });
    }
    let mut rows = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for (i, l) in lines.enumerate() {
        if l.trim().is_empty() {
            continue;
        }
        let row = RunRow::parse(l).and_then(|r| {
            r.check(meta)?;
            if !seen.insert(r.seed) {
                return Err(format!("seed {} appears twice", r.seed));
            }
            Ok(r)
        });
        match row {
            Ok(r) => rows.push(r),
            Err(error) => {
                return Err(BatchError::Row {
                    path: csv,
                    line: i + 2,
                    error,
                });
            }
        }
    }
    if rows.len() != meta.runs {
        return Err(BatchError::RowCount {
            path: csv,
            rows: rows.len(),
            runs: meta.runs,
        });
    }
    // A shard as `batch` wrote it holds every seed of its shard.
    let own = meta.shard.items(meta.seeds.len());
    if meta.merged_shards.is_empty() && rows.len() as u64 != own {
        return Err(BatchError::ShardSeeds {
            path: csv,
            rows: rows.len(),
            shard: meta.shard,
            seeds: meta.seeds,
            own,
        });
    }
    Ok((sf.meta, sf.aggregate, rows))
}

/// Merges shard directories of one study into `out` (see the module docs).
/// With `allow_partial`, missing seeds are allowed (the summary says how many
/// runs it holds).
pub fn merge(inputs: &[PathBuf], out: &Path, allow_partial: bool) -> Result<BatchReport> {
    let mut parts = Vec::new();
    for d in inputs {
        parts.push(read_dir(d)?);
    }
    let shards = merged_shards(
        "batch",
        "family, seeds, planner, perception, overrides, solver, rate and shard count",
        inputs,
        &parts,
        |(m, _, _)| {
            (
                m.study_key(),
                m.shard.index,
                &m.merged_shards[..],
                m.shard.count,
            )
        },
    )?;
    let wall = parts.iter().fold(0.0, |w, (m, _, _)| w + m.wall_time_s);
    let mut rows: Vec<RunRow> = parts
        .iter()
        .flat_map(|(_, _, r)| r.iter().cloned())
        .collect();
    rows.sort_by_key(|r| r.seed);
    if let Some(w) = rows.windows(2).find(|w| w[0].seed == w[1].seed) {
        return Err(BatchError::SeedTwice(w[0].seed));
    }
    let m0 = &parts[0].0;
    let expected = m0.seeds.len();
    if !allow_partial && (rows.len() as u64) < expected {
        let missing = missing_shards(&shards, m0.shard.count);
        return Err(BatchError::Incomplete {
            runs: rows.len(),
            expected,
            missing: if missing.is_empty() {
                "none, but seeds are missing".into()
            } else {
                missing.join(", ")
            },
        });
    }
    let meta = BatchMeta {
        shard: Shard::ALL,
        merged_shards: shards,
        jobs: 0,
        wall_time_s: wall,
        runs: rows.len(),
        ..m0.clone()
    };
    let agg = aggregate(&rows);
    let out_dir = write_dir(out, &meta, &rows, &agg)?;
    Ok(BatchReport {
        out_dir,
        meta,
        rows,
        aggregate: agg,
    })
}
