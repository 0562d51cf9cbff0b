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

use anyhow::{Context, Result, bail};
use ldcbf_controller::{Config, CycleInput, CycleOutput, RecordedInput, RobotController};

use crate::sense::Perception;
use crate::sim::{HORIZON, SimOptions, SimResult, Solver, run};
use crate::studies::deadline::Case;
use crate::world::{MAX_VERTICES, Polygon};

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
    pub fn from_run(label: &str, result: &SimResult) -> Result<Recording> {
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
                _ => bail!(
                    "{label}: no plant sample at t = {} s for cycle {}",
                    c.time,
                    c.index
                ),
            };
            while foot + 1 < result.footsteps.len() && result.footsteps[foot + 1].time <= c.time {
                foot += 1;
            }
            let f = result
                .footsteps
                .get(foot)
                .with_context(|| format!("{label}: no footsteps"))?;
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
                    _ => bail!(
                        "{label}: no LiDAR scan for cycle {} (run with record_scans)",
                        c.index
                    ),
                }
            } else {
                0
            };
            if f.side != s.stance_side {
                bail!(
                    "{label}: cycle {}: stance foot {} is on the {:?} side, the plant's stance is {:?}",
                    c.index,
                    f.index,
                    f.side,
                    s.stance_side
                );
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
    pub fn controller(&self) -> Result<RobotController> {
        RobotController::new(self.config)
            .map_err(|e| anyhow::anyhow!("{}: controller: {e}", self.label))
    }

    /// Replays every input in order through a fresh controller (own solver,
    /// warm start carried as in the loop) and checks that each output is the
    /// logged one, bit for bit (compared through their `Debug` forms, so NaN
    /// fields compare equal). The first mismatch is the error.
    pub fn verify(&self) -> Result<()> {
        if !self.own_solver {
            bail!(
                "{}: the run used Clarabel; the replay uses the own solver",
                self.label
            );
        }
        let mut ctl = self.controller()?;
        for (i, logged) in self.outputs.iter().enumerate() {
            let input = self
                .input(i)
                .with_context(|| format!("{}: cycle {i} has no input", self.label))?;
            let out = ctl.step(&input, None);
            let (a, b) = (format!("{out:?}"), format!("{logged:?}"));
            if a != b {
                bail!(
                    "{}: cycle {i}: the replay returned\n  {a}\nthe run logged\n  {b}",
                    self.label
                );
            }
        }
        if self.inputs.len() != self.outputs.len() {
            bail!(
                "{}: {} inputs for {} outputs",
                self.label,
                self.inputs.len(),
                self.outputs.len()
            );
        }
        Ok(())
    }
}

/// Runs `case` to its end exactly as `ldcbf-sim deadline` does (own solver,
/// 20 Hz, no clearances), keeping the LiDAR scans, and returns its recording.
/// `sets` are `--set` overrides for the scenario.
pub fn record_case(case: &Case, sets: &[(String, String)]) -> Result<Recording> {
    let sc = case.load(sets)?;
    let opts = SimOptions {
        record_scans: sc.perception == Perception::Lidar,
        record_clearance: false,
        ..SimOptions::default()
    };
    let res = run(&sc, opts).with_context(|| format!("case {}", case.label()))?;
    Recording::from_run(&case.label(), &res)
}
