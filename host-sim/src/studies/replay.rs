//! The controller inputs of a finished run, rebuilt from its logs, so that its
//! control cycles can be replayed outside the loop (the benchmarks of
//! `benches/recorded.rs`, per-cycle timing).
//!
//! No hook in the loop is needed: the logs of [`crate::sim::run`] hold every
//! part of each cycle's [`CycleInput`].
//!
//! * CoM position and velocity, heading, turning rate in force and stance side:
//!   the 1 kHz [`Sample`](crate::sim::Sample) of the tick of the call (the
//!   sample is taken after the control call and before the tick is integrated,
//!   from the same plant state; cycle and sample share `Plant::time`);
//! * stance foot: the last [`Footstep`](crate::sim::Footstep) that became the
//!   stance foot at or before the call (a step ends before the control call of
//!   its tick);
//! * time in step and goal (the current subgoal): the
//!   [`CycleRecord`](crate::sim::CycleRecord);
//! * obstacles: the scenario's map (known map), or the obstacles inferred from
//!   the cycle's scan (LiDAR; needs [`SimOptions::record_scans`]).
//!
//! [`Recording::verify`] replays the inputs through a fresh controller with the
//! run's configuration and checks that every output is the one the run logged,
//! bit for bit (with the own solver the controller is deterministic), so a
//! change of the loop that breaks one of the correspondences above is caught
//! (`host-sim/tests/replay.rs`).
//!
//! Frames and units: world frame W; m, m/s, rad, rad/s, s.

use ldcbf_controller::{
    Config, ConfigError, CycleInput, CycleOutput, RecordedInput, RobotController, Side,
};

use crate::sense::Perception;
use crate::sim::{HORIZON, SimOptions, SimResult, Solver, run};
use crate::studies::deadline::{Case, DeadlineError};
use crate::world::{MAX_VERTICES, Polygon};

/// Why a recording could not be built or replayed; each names the run's label
/// (and the cycle where there is one). Cycle indices count from 0; times in s.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// A cycle has no plant sample of its tick (a truncated result).
    #[error("{label}: no plant sample at t = {time} s for cycle {cycle}")]
    NoSample {
        /// The run's label.
        label: String,
        /// Simulated time of the cycle, s.
        time: f64,
        /// The cycle's index.
        cycle: usize,
    },
    /// The run logged no footstep.
    #[error("{label}: no footsteps")]
    NoFootsteps {
        /// The run's label.
        label: String,
    },
    /// A LiDAR run has no scan of a cycle (run without `record_scans`).
    #[error("{label}: no LiDAR scan for cycle {cycle} (run with record_scans)")]
    NoScan {
        /// The run's label.
        label: String,
        /// The cycle's index.
        cycle: usize,
    },
    /// The last logged footstep is not on the plant's stance side.
    #[error(
        "{label}: cycle {cycle}: stance foot {foot} is on the {side:?} side, the plant's stance is {stance:?}"
    )]
    StanceSide {
        /// The run's label.
        label: String,
        /// The cycle's index.
        cycle: usize,
        /// The footstep's index.
        foot: u32,
        /// The footstep's side.
        side: Side,
        /// The plant's stance side in the cycle's sample.
        stance: Side,
    },
    /// The controller refused the run's configuration.
    #[error("{label}: controller: {error}")]
    Controller {
        /// The run's label.
        label: String,
        /// Why.
        error: ConfigError,
    },
    /// The run used Clarabel, the replay the own solver.
    #[error("{label}: the run used Clarabel; the replay uses the own solver")]
    Clarabel {
        /// The run's label.
        label: String,
    },
    /// A logged output has no input.
    #[error("{label}: cycle {cycle} has no input")]
    NoInput {
        /// The run's label.
        label: String,
        /// The cycle's index.
        cycle: usize,
    },
    /// The replay's output differs from the logged one (their `Debug` forms).
    #[error("{label}: cycle {cycle}: the replay returned\n  {replay}\nthe run logged\n  {logged}")]
    Mismatch {
        /// The run's label.
        label: String,
        /// The cycle's index.
        cycle: usize,
        /// The replay's output.
        replay: String,
        /// The logged output.
        logged: String,
    },
    /// Inputs and outputs differ in number.
    #[error("{label}: {inputs} inputs for {outputs} outputs")]
    Count {
        /// The run's label.
        label: String,
        /// Number of inputs.
        inputs: usize,
        /// Number of outputs.
        outputs: usize,
    },
    /// The case could not be loaded or run ([`record_case`]).
    #[error(transparent)]
    Case(#[from] DeadlineError),
}

/// Every control cycle of one run, ready to replay in order.
#[derive(Clone, Debug)]
pub struct Recording {
    /// The run's label (e.g. [`Case::label`]).
    pub label: String,
    /// The controller configuration the run used (scenario defaults and
    /// overrides).
    pub config: Config,
    /// Obstacle lists, world frame: the map alone (known map), or one per cycle
    /// (LiDAR).
    pub obstacle_sets: Vec<Vec<Polygon>>,
    /// The inputs, one per control cycle, in order.
    pub inputs: Vec<RecordedInput>,
    /// What the run's controller returned for each input.
    pub outputs: Vec<CycleOutput<HORIZON>>,
    /// The run used the own QP solver ([`Solver::Own`]); only then can the
    /// replay be compared with the outputs ([`Recording::verify`]).
    pub own_solver: bool,
}

impl Recording {
    /// Rebuilds the inputs of every control cycle of `result` (see the module
    /// docs). Fails if a cycle has no sample of its tick (a truncated result)
    /// or, with LiDAR, no scan (run without [`SimOptions::record_scans`]).
    pub fn from_run(label: &str, result: &SimResult) -> Result<Recording, ReplayError> {
        let lidar = result.scenario.perception == Perception::Lidar;
        let mut obstacle_sets = Vec::new();
        if !lidar {
            obstacle_sets.push(result.scenario.obstacles.clone());
        }
        let mut inputs = Vec::with_capacity(result.cycles.len());
        let (mut sample, mut foot, mut scan) = (0usize, 0usize, 0usize);
        for c in &result.cycles {
            // Samples and footsteps are in time order, as are the cycles.
            while sample < result.samples.len() && result.samples[sample].time < c.time {
                sample += 1;
            }
            let s = match result.samples.get(sample) {
                Some(s) if s.time == c.time => s,
                _ => {
                    return Err(ReplayError::NoSample {
                        label: label.to_string(),
                        time: c.time,
                        cycle: c.index,
                    });
                }
            };
            while foot + 1 < result.footsteps.len() && result.footsteps[foot + 1].time <= c.time {
                foot += 1;
            }
            let f = result
                .footsteps
                .get(foot)
                .ok_or_else(|| ReplayError::NoFootsteps {
                    label: label.to_string(),
                })?;
            let mut speed_cap = ldcbf_controller::NO_SPEED_CAP;
            let obstacles = if lidar {
                while scan < result.scans.len() && result.scans[scan].cycle < c.index {
                    scan += 1;
                }
                match result.scans.get(scan) {
                    Some(sc) if sc.cycle == c.index => {
                        speed_cap = sc.speed_cap;
                        obstacle_sets.push(sc.obstacles.clone());
                        obstacle_sets.len() - 1
                    }
                    _ => {
                        return Err(ReplayError::NoScan {
                            label: label.to_string(),
                            cycle: c.index,
                        });
                    }
                }
            } else {
                0
            };
            if f.side != s.stance_side {
                return Err(ReplayError::StanceSide {
                    label: label.to_string(),
                    cycle: c.index,
                    foot: f.index,
                    side: f.side,
                    stance: s.stance_side,
                });
            }
            inputs.push(RecordedInput {
                com_position: s.position,
                com_velocity: s.velocity,
                heading: s.heading,
                turning_rate: s.turning_rate,
                stance_foot: f.position,
                stance_side: s.stance_side,
                time_in_step: c.time_in_step,
                goal: c.goal,
                obstacles,
                speed_cap,
            });
        }
        Ok(Recording {
            label: label.to_string(),
            config: result.scenario.config,
            obstacle_sets,
            inputs,
            outputs: result.cycles.iter().map(|c| c.output).collect(),
            own_solver: result.options.solver == Solver::Own,
        })
    }

    /// Number of recorded cycles.
    pub fn len(&self) -> usize {
        self.inputs.len()
    }

    /// No cycle was recorded.
    pub fn is_empty(&self) -> bool {
        self.inputs.is_empty()
    }

    /// The controller input of cycle `i` (`None` past the end).
    pub fn input(&self, i: usize) -> Option<CycleInput<'_, MAX_VERTICES>> {
        let r = self.inputs.get(i)?;
        Some(r.input(self.obstacle_sets.get(r.obstacles)?))
    }

    /// A fresh controller with the run's configuration (as the run started).
    pub fn controller(&self) -> Result<RobotController, ReplayError> {
        RobotController::new(self.config).map_err(|error| ReplayError::Controller {
            label: self.label.clone(),
            error,
        })
    }

    /// Replays every input in order through a fresh controller (own solver,
    /// warm start carried as in the loop) and checks that each output is the
    /// logged one, bit for bit (compared through their `Debug` forms, so NaN
    /// fields compare equal). The first mismatch is the error.
    pub fn verify(&self) -> Result<(), ReplayError> {
        let label = || self.label.clone();
        if !self.own_solver {
            return Err(ReplayError::Clarabel { label: label() });
        }
        let mut ctl = self.controller()?;
        for (i, logged) in self.outputs.iter().enumerate() {
            let input = self.input(i).ok_or_else(|| ReplayError::NoInput {
                label: label(),
                cycle: i,
            })?;
            let out = ctl.step(&input, None);
            let (a, b) = (format!("{out:?}"), format!("{logged:?}"));
            if a != b {
                return Err(ReplayError::Mismatch {
                    label: label(),
                    cycle: i,
                    replay: a,
                    logged: b,
                });
            }
        }
        if self.inputs.len() != self.outputs.len() {
            return Err(ReplayError::Count {
                label: label(),
                inputs: self.inputs.len(),
                outputs: self.outputs.len(),
            });
        }
        Ok(())
    }
}

/// Runs `case` to its end exactly as `ldcbf-sim deadline` does (own solver,
/// 20 Hz, no clearances), keeping the LiDAR scans, and returns its recording.
/// `sets` are `--set` overrides for the scenario.
pub fn record_case(case: &Case, sets: &[(String, String)]) -> Result<Recording, ReplayError> {
    let sc = case.load(sets)?;
    let opts = SimOptions {
        record_scans: sc.perception == Perception::Lidar,
        record_clearance: false,
        ..SimOptions::default()
    };
    let res = run(&sc, opts).map_err(|source| DeadlineError::Run {
        label: case.label(),
        source,
    })?;
    Recording::from_run(&case.label(), &res)
}
