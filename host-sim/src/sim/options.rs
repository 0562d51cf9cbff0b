//! What a run is asked to do besides its scenario ([`SimOptions`]: the QP
//! solver, the controller rate, what to record, the timings per call) and why
//! it could not start or stopped early ([`SimError`]).

use crate::plant::PlantError;
use crate::sim::cancel;
#[cfg(doc)]
use crate::sim::{CycleRecord, Sample, SimResult, run};

/// Which QP solver runs inside the controller.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// The controller's own dual active-set solver.
    Own,
    /// Clarabel, through `ldcbf_reference::ClarabelBackend` (reference in the loop).
    Clarabel,
}

/// How often the controller runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MpcRate {
    /// At a fixed rate in Hz (20 Hz in the paper): one call every
    /// `round(1000 / hz)` plant ticks, starting at t = 0.
    Hz(u32),
    /// Once per step, at its start (`time_in_step = 0`), as the report did.
    PerStep,
}

impl core::str::FromStr for MpcRate {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "step" {
            return Ok(MpcRate::PerStep);
        }
        let hz = s.trim_end_matches("hz").trim_end_matches("Hz");
        match hz.parse::<u32>() {
            Ok(h) if (1..=1000).contains(&h) => Ok(MpcRate::Hz(h)),
            _ => Err(format!(
                "expected `step` or a rate in Hz in 1..=1000 (e.g. 20), got {s:?}"
            )),
        }
    }
}

impl core::fmt::Display for MpcRate {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MpcRate::Hz(h) => write!(f, "{h} Hz"),
            MpcRate::PerStep => f.write_str("once per step"),
        }
    }
}

/// Simulation options (not part of the scenario).
#[derive(Clone, Copy, Debug)]
pub struct SimOptions {
    /// QP solver.
    pub solver: Solver,
    /// Controller rate.
    pub mpc_rate: MpcRate,
    /// Keep every LiDAR scan (points and inferred polygons) in
    /// [`SimResult::scans`] for the figures; batch runs turn it off.
    pub record_scans: bool,
    /// Keep every cycle's QP (as the controller assembled it) in
    /// [`SimResult::qps`], for `run --export-qps`.
    pub record_qps: bool,
    /// Measure every 1 kHz CoM sample's clearance to the true obstacles
    /// ([`Sample::clearance`]). Off, the samples' clearance is NaN, so the
    /// summary's CoM clearance and collision flag mean nothing; the walk itself
    /// is the same (the controller and the end conditions never read it). The
    /// deadline study turns it off: in a debug build it is most of a run's time.
    pub record_clearance: bool,
    /// Timings of each controller call, `K >= 1` (0 is refused by [`run`]).
    /// With `K > 1` the call is also timed `K - 1` times on clones of the
    /// controller and the QP backend made just before it (the same input, the
    /// same state, so the same computation) and [`CycleRecord::compute_ns`] is
    /// the minimum of the `K` timings: a preemption or a cache miss that hit one
    /// timing does not count, a cycle that is slow every time does. The run's
    /// results do not depend on `K` (the loop keeps the output of the
    /// controller's own call); it costs `K` times the controller's time.
    pub timing_repeats: u32,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            solver: Solver::Own,
            mpc_rate: MpcRate::Hz(20),
            record_scans: true,
            record_qps: false,
            record_clearance: true,
            timing_repeats: 1,
        }
    }
}

/// Largest [`SimOptions::timing_repeats`]: the controller's time grows
/// `K`-fold, so a run stays bounded (a 300-cycle walk at 10,000 repeats of
/// 1-20 µs calls: 3-60 s more).
pub const MAX_TIMING_REPEATS: u32 = 10_000;

/// Why a run could not start, or why it stopped early. The messages are the
/// ones the CLI prints; no variant has a `source` (the CLI prints the chain,
/// which would repeat the inner message).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// [`SimOptions::timing_repeats`] is 0.
    #[error("timing repeats must be >= 1, got 0")]
    NoTimingRepeats,
    /// [`SimOptions::timing_repeats`] is above [`MAX_TIMING_REPEATS`].
    #[error("timing repeats must be at most {MAX_TIMING_REPEATS}, got {0}")]
    TooManyTimingRepeats(u32),
    /// The controller refused the scenario's configuration.
    #[error("controller: {0}")]
    Controller(ldcbf_controller::ConfigError),
    /// The plant refused its parameters.
    #[error("plant: {0}")]
    Plant(PlantError),
    /// The true map's obstacles could not be indexed.
    #[error("{0}")]
    Map(String),
    /// The LiDAR mapping could not start.
    #[error("{0}")]
    Mapping(String),
    /// Cancelled by a signal or the caller's flag, mid-run.
    #[error("{0}")]
    Cancelled(cancel::Cancelled),
}
