//! The `run` pipeline behind `ldcbf-sim run`: load and validate the scenario,
//! simulate, write the logs and figures into a temporary directory, and move it
//! into place only when everything succeeded (see [`crate::report::OutputDir`]).

use std::path::{Component, Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::report::plot::PlotOptions;
use crate::report::{OutputDir, Summary, summarize, write_logs};
use crate::scenario::{LoadOptions, load};
use crate::sim::{MpcRate, SimOptions, SimResult, Solver, run};

/// Everything `ldcbf-sim run` needs.
#[derive(Clone, Debug)]
pub struct RunRequest {
    /// Scenario name (`scenarios/<name>.toml`) or path.
    pub scenario: String,
    /// Output directory; default `out/<name>` (`out/<name>-seed<S>` for a
    /// scenario with a generator).
    pub out: Option<PathBuf>,
    /// Seed (generator).
    pub seed: Option<u64>,
    /// `--set key=value` overrides.
    pub sets: Vec<(String, String)>,
    /// QP solver.
    pub solver: Solver,
    /// Controller rate.
    pub mpc_rate: MpcRate,
    /// Render the PNG figures.
    pub plots: bool,
    /// Render `walk.gif` (only with `plots`).
    pub gif: bool,
    /// Write every n-th 1 kHz sample to `trajectory.csv` (and to `/tf` in
    /// `run.mcap`).
    pub trajectory_every: usize,
    /// Write `run.mcap` ([`crate::report::mcap`]).
    pub mcap: bool,
    /// Also write every cycle's QP as `cycle_NNNNN.npz` (`P, q, G, h`) into this
    /// directory (created atomically like the output directory).
    pub export_qps: Option<PathBuf>,
    /// Timings of each controller call, `>= 1` ([`SimOptions::timing_repeats`]:
    /// `compute_ns` in `cycles.csv` is their minimum; the run is the same).
    pub timing_repeats: u32,
}

impl RunRequest {
    /// A request with the defaults of the CLI: own solver, 20 Hz, all figures,
    /// trajectory at 100 Hz, `run.mcap`, one timing per controller call.
    pub fn new(scenario: &str) -> Self {
        RunRequest {
            scenario: scenario.into(),
            out: None,
            seed: None,
            sets: Vec::new(),
            solver: Solver::Own,
            mpc_rate: MpcRate::Hz(20),
            plots: true,
            gif: true,
            trajectory_every: 10,
            mcap: true,
            export_qps: None,
            timing_repeats: 1,
        }
    }
}

/// What a finished run produced.
#[derive(Debug)]
pub struct RunReport {
    /// The summary (also in `summary.json`).
    pub summary: Summary,
    /// The output directory.
    pub out_dir: PathBuf,
    /// Files written, relative to `out_dir`.
    pub files: Vec<String>,
    /// The full result (logs in memory).
    pub result: SimResult,
    /// What the user should know about the scenario before trusting the
    /// run (e.g. an obstacle corner sharper than the LiDAR sees in time).
    pub warnings: Vec<String>,
}

/// `a` and `b` name the same directory or one lies inside the other (compared
/// lexically after making them absolute; `..` is resolved lexically too).
fn overlapping(a: &Path, b: &Path) -> bool {
    let norm = |p: &Path| -> PathBuf {
        let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let mut out = PathBuf::new();
        for c in abs.components() {
            match c {
                Component::CurDir => {}
                Component::ParentDir => {
                    out.pop();
                }
                c => out.push(c),
            }
        }
        out
    };
    let (a, b) = (norm(a), norm(b));
    a.starts_with(&b) || b.starts_with(&a)
}

/// Runs the request. Errors (bad scenario, an unusable output location, I/O)
/// leave no output directory: both output directories are checked and created
/// (as temporary siblings) before the simulation and moved into place only at
/// the end.
pub fn execute_run(req: &RunRequest) -> Result<RunReport> {
    if req.timing_repeats == 0 {
        bail!("--repeat must be >= 1 (timings of each control cycle), got 0");
    }
    if req.timing_repeats > crate::sim::MAX_TIMING_REPEATS {
        bail!(
            "--repeat must be at most {} (timings of each control cycle), got {}",
            crate::sim::MAX_TIMING_REPEATS,
            req.timing_repeats
        );
    }
    let scenario = load(
        &req.scenario,
        &LoadOptions {
            seed: req.seed,
            sets: req.sets.clone(),
        },
    )?;
    let out = req.out.clone().unwrap_or_else(|| {
        let name = if scenario.generator.is_some() {
            format!("{}-seed{}", scenario.name, scenario.seed)
        } else {
            scenario.name.clone()
        };
        PathBuf::from("out").join(name)
    });
    if let Some(qdir) = &req.export_qps {
        if overlapping(qdir, &out) {
            bail!(
                "--export-qps {}: must be a directory apart from the output directory {} \
                 (neither inside the other)",
                qdir.display(),
                out.display()
            );
        }
        OutputDir::preflight(qdir).with_context(|| format!("--export-qps {}", qdir.display()))?;
    }
    let dir = OutputDir::create(&out).with_context(|| format!("--out {}", out.display()))?;
    let qd = match &req.export_qps {
        Some(qdir) => Some(
            OutputDir::create(qdir).with_context(|| format!("--export-qps {}", qdir.display()))?,
        ),
        None => None,
    };
    let result = run(
        &scenario,
        SimOptions {
            solver: req.solver,
            mpc_rate: req.mpc_rate,
            record_scans: req.plots,
            record_qps: req.export_qps.is_some(),
            record_clearance: true,
            timing_repeats: req.timing_repeats,
        },
    )?;
    if let Some(qd) = &qd {
        for (cycle, p) in &result.qps {
            p.write_npz(&qd.path().join(format!("cycle_{cycle:05}.npz")))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
        }
    }
    crate::sim::cancel::check()?;
    let summary = summarize(&result);
    write_logs(&result, &summary, dir.path(), req.trajectory_every)
        .with_context(|| format!("--out {}: cannot write the logs", out.display()))?;
    let mut files: Vec<String> = [
        "summary.json",
        "cycles.csv",
        "footsteps.csv",
        "trajectory.csv",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if req.mcap {
        crate::report::mcap::write_mcap(
            &result,
            &dir.path().join("run.mcap"),
            req.trajectory_every,
        )
        .with_context(|| format!("--out {}: cannot write run.mcap", out.display()))?;
        files.push("run.mcap".into());
    }
    if req.plots {
        let opts = PlotOptions {
            gif: req.gif,
            ..PlotOptions::default()
        };
        files.extend(crate::report::plot::render_all(&result, dir.path(), &opts)?);
    }
    // Everything is written (unless a signal came meanwhile): move the QPs,
    // then the results, into place.
    crate::sim::cancel::check()?;
    if let (Some(qd), Some(qdir)) = (qd, &req.export_qps) {
        qd.commit()
            .with_context(|| format!("cannot move the QPs into {}", qdir.display()))?;
    }
    let out_dir = dir
        .commit()
        .with_context(|| format!("cannot move the results into {}", out.display()))?;
    Ok(RunReport {
        warnings: scenario_warnings(&scenario),
        summary,
        out_dir,
        files,
        result,
    })
}

/// The scenario's warnings: with `perception = "lidar"`, each obstacle whose
/// sharpest corner is below the smallest tip angle the LiDAR meets in time
/// ([`crate::sense::detect::sharp_corners`], docs/safety.md "Thin tips and
/// the ray spacing").
fn scenario_warnings(scenario: &crate::scenario::Scenario) -> Vec<String> {
    if scenario.perception != crate::sense::Perception::Lidar {
        return Vec::new();
    }
    let c = &scenario.config;
    crate::sense::detect::sharp_corners(
        &scenario.obstacles,
        scenario.lidar.rays,
        c.body_radius,
        c.barrier_margin(),
    )
    .iter()
    .map(|s| {
        format!(
            "obstacles[{}]: a corner of {:.2} degrees, sharper than the {:.2} degrees \
             {} LiDAR rays meet in time at this margin; pointed at the robot it may \
             touch the body (docs/safety.md, \"Thin tips and the ray spacing\")",
            s.obstacle,
            s.angle.to_degrees(),
            s.limit.to_degrees(),
            scenario.lidar.rays
        )
    })
    .collect()
}
