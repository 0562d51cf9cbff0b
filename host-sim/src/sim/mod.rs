//! The closed loop: the 1 kHz [`Plant`](crate::plant::Plant) and the controller, called as an onboard
//! loop would call it. A room of the simulator above the scenario, the plant,
//! perception and the planner; the report and the studies read what it
//! records ([`SimResult`]).
//!
//! Before the first tick, with `planner = "rrt_star"` and the known map,
//! [`crate::plan::plan`] turns the map into subgoals (the goal last; without a planner the goal
//! is the only subgoal). If planning fails the run goes on towards the goal
//! directly and the error is kept in [`Navigation::error`].
//!
//! Each tick, in this order:
//!
//! Every tick first moves the moving obstacles to the plant's time
//! ([`crate::world::moving`]: polygon at t = 0 plus velocity times time)
//! and steps the people who react to it (`people.rs`,
//! [`crate::world::crowd`]: they choose velocities at 20 Hz, seeing the
//! robot's CoM and CoM velocity when they see the robot, and move every
//! tick).
//!
//! 0. **Push.** A push of the scenario's `[disturbance]` due at this tick is
//!    added to the plant's CoM velocity ([`crate::plant::disturbance`]), so everything
//!    below sees the pushed state.
//! 1. **Step end.** When the current step has lasted `T`, the swing foot lands at
//!    the `foot_target` of the most recent controller cycle, the stance side
//!    flips, and the `turning_rate` of that cycle takes effect for the new step
//!    (the controller plans `omega_bar` for the step that starts at `x_0`,
//!    [`ldcbf_controller::CycleOutput::turning_rate`]). With a foot placement
//!    error (`disturbance.foot_sigma`) the foot lands off the target by a seeded
//!    Gaussian draw; the landed position is the stance foot from then on.
//! 2. **Control.** At 20 Hz (every 50 ticks; `MpcRate::Hz`) or once at the start of
//!    every step (`MpcRate::PerStep`), a [`CycleInput`](ldcbf_controller::CycleInput) is built from the plant's
//!    true state (CoM position, velocity, heading, the turning rate in force, stance
//!    foot and side, time in step), the goal and the obstacle list, and
//!    `Controller::step` is called (the controller holds the QP backend,
//!    [`Solver`]). With the known map, the candidates
//!    come from the map's R-tree ([`crate::world::obstacle_index`], built once before
//!    the first tick) around `Controller::obstacle_query` (reused while they
//!    cover the cycle, [`crate::world::obstacle_index::Candidates`]), and
//!    `Controller::step` is called on them: bit for bit the
//!    result of `step` on the whole map, at a cost that does not grow with
//!    it. The wall-clock time is measured with [`Instant`](std::time::Instant) around that query
//!    and call only; with [`SimOptions::timing_repeats`]
//!    `K > 1`, the same call is first timed `K - 1` times on clones of the
//!    controller (with its QP backend) made just before it, i.e. on the same
//!    input and the same state, and the cycle's time is the minimum of the `K`
//!    timings; the loop goes on with the result of the controller's own call,
//!    so the closed loop does not depend on `K`. Before the call, the current subgoal
//!    is advanced while the CoM is within `switch_radius` of it (never past the
//!    goal), and the controller's goal is the current subgoal. With
//!    `perception = "lidar"` a LiDAR scan taken at that moment from the CoM
//!    updates the occupancy map and the obstacle list is the map's pieces
//!    near the robot, at rest; with `lidar.track_moving` the scan's people
//!    ([`crate::sense::movers`]: person-sized clusters not confirmed at rest,
//!    kept out of the map) follow, with their tracked velocities; with `planner = "rrt_star"` the
//!    subgoals are planned and replanned on that map ([`MappingLog`]);
//!    otherwise it is the true map at that tick ([`crate::world::moving`])
//!    with the obstacles' true velocities. With state estimation noise (`disturbance.noise_*`)
//!    the CoM position, velocity and heading in the input (and the position
//!    used to advance the subgoal) are the true ones plus a seeded Gaussian
//!    draw; the LiDAR scans from the true pose.
//! 3. **Record** the 1 kHz sample (and its clearance to every TRUE obstacle at
//!    its position at that tick, and the contacts of the body and the stance
//!    foot with who moved into whom, [`Contact`];
//!    [`clearance`](crate::world::clearance) found through the map's index, unless
//!    [`SimOptions::record_clearance`] is off), then
//!    check the end conditions: goal reached (`|p - goal| <= success_radius`),
//!    time limit, or stuck: the remaining path length
//!    ([`crate::plan::remaining_length`]: distance to the current subgoal plus
//!    the rest of the subgoal polyline; the distance to the goal without a
//!    planner) has not improved by 5 cm for `stuck_window` seconds. Walking
//!    around an obstacle towards a subgoal is progress; circling is not. A
//!    cycle whose input the controller rejects as invalid (a state out of
//!    range: the pendulum is falling) ends the run as `diverged`.
//! 4. **Integrate** one tick (with `disturbance.plant_com_height`, the plant's
//!    `beta` is that height's, not the controller model's).
//!
//! The simulator never reaches inside the controller: it uses the returned
//! [`ldcbf_controller::CycleOutput`] to drive the plant and reads
//! `Controller::last_assembly` only to log the cycle's LDCBF half-planes for the
//! figures.
//!
//! The loop is `closed_loop::Loop`: its set-up, one method per step of a tick
//! (`land`, `control` with `perceive` and `log_cycle`, `record`,
//! `end_condition`) and `finish`, which returns the [`SimResult`].

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{CycleOutput, HalfPlane, OwnSolver, QpBackend, Side};
use ldcbf_reference::ClarabelBackend;

use crate::plan::Route;
use crate::plant::disturbance::DisturbanceLog;
use crate::scenario::Scenario;
use crate::world::Polygon;

pub mod cancel;
pub mod capture;
mod closed_loop;
mod contacts;
mod options;
mod people;
pub use contacts::{Contact, ContactCause, ContactPart, STANDING_SPEED, contact_counts};
pub use options::{MAX_TIMING_REPEATS, MpcRate, SimError, SimOptions, Solver};

/// Horizon of [`RobotController`](ldcbf_controller::RobotController).
pub const HORIZON: usize = 3;
/// QP variables of [`RobotController`](ldcbf_controller::RobotController).
pub const NV: usize = 2 * HORIZON;
/// QP row capacity of [`RobotController`](ldcbf_controller::RobotController).
pub const NC: usize = ldcbf_controller::constraint_capacity(HORIZON, 8, true);

/// Plant tick, s (1 kHz).
pub const PLANT_DT: f64 = 1e-3;

/// Why the run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The CoM came within `success_radius` of the goal.
    GoalReached,
    /// The simulated-time limit was hit.
    TimeLimit,
    /// No progress towards the goal for `stuck_window` seconds.
    Stuck,
    /// The walk diverged: the controller rejected the measured state as out of
    /// range (`CycleStatus::InvalidInput`, e.g. a CoM speed above
    /// `ldcbf_controller::mpc::MAX_RATE`), i.e. the pendulum is falling. The run
    /// stops at that cycle instead of integrating the fall.
    Diverged,
}

impl Outcome {
    /// Short name for logs.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::GoalReached => "goal_reached",
            Outcome::TimeLimit => "time_limit",
            Outcome::Stuck => "stuck",
            Outcome::Diverged => "diverged",
        }
    }
}

/// One LDCBF half-plane used by a cycle (for the figures).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActiveHalfPlane {
    /// Index of the obstacle in the scenario's list.
    pub obstacle: usize,
    /// The half-plane: `c` (m) and unit `eta`, world frame.
    pub half_plane: HalfPlane,
}

/// One control cycle, as logged.
#[derive(Clone, Debug)]
pub struct CycleRecord {
    /// Cycle index from 0.
    pub index: usize,
    /// Simulated time of the call, s.
    pub time: f64,
    /// Time already spent in the current step, s.
    pub time_in_step: f64,
    /// Index of the step in progress (0 = the first step).
    pub step: u32,
    /// Stance side during the call.
    pub stance_side: Side,
    /// Goal given to the controller, m.
    pub goal: Vector2<f64>,
    /// What the controller returned.
    pub output: CycleOutput<HORIZON>,
    /// Wall-clock time of the controller call (with the known map, the index
    /// query and the call), ns: with
    /// [`SimOptions::timing_repeats`] `K > 1`, the minimum over the `K` timings
    /// of the call on the same input and state.
    pub compute_ns: u64,
    /// This cycle's `foot_target` is where the swing foot actually landed (it was
    /// the last cycle before a step end).
    pub landed: bool,
    /// The LDCBF half-planes of the cycle (active obstacles, nearest first). With
    /// LiDAR, `obstacle` indexes that cycle's inferred obstacles.
    pub half_planes: Vec<ActiveHalfPlane>,
    /// Index of the current subgoal in [`Navigation::subgoals`].
    pub subgoal: usize,
    /// Obstacles handed to the controller (the true map's size, or the number
    /// inferred from this cycle's scan).
    pub obstacles_seen: usize,
}

/// One LiDAR scan and what was inferred from it.
#[derive(Clone, Debug)]
pub struct ScanRecord {
    /// The control cycle it fed.
    pub cycle: usize,
    /// Sensor position (the CoM), m.
    pub origin: Vector2<f64>,
    /// Noisy hit points, m (world).
    pub points: Vec<Vector2<f64>>,
    /// Inferred obstacles (one per DBSCAN cluster), world frame.
    pub obstacles: Vec<Polygon>,
    /// The cycle's speed cap, m/s (`crate::sim::capture`; infinite without).
    pub speed_cap: f64,
}

/// The planner's part of a run.
#[derive(Clone, Debug, Default)]
pub struct Navigation {
    /// The RRT* plan (tree, path, grid), when planned and found.
    pub plan: Option<Route>,
    /// Why planning failed (the run then walked to the goal directly).
    pub error: Option<String>,
    /// Wall-clock planning time, ns (0 without a planner).
    pub plan_time_ns: u64,
    /// Subgoals in order, the goal last, m.
    pub subgoals: Vec<Vector2<f64>>,
    /// Simulated time at which each subgoal was passed (switch or goal), s.
    pub reached_at: Vec<f64>,
}

/// One footstep (a stance foot).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Footstep {
    /// Step index: 0 is the initial stance foot, `k` the foot landed at the end of
    /// step `k - 1`.
    pub index: u32,
    /// Position, m (world).
    pub position: Vector2<f64>,
    /// Which foot.
    pub side: Side,
    /// Time it became the stance foot, s.
    pub time: f64,
    /// Heading of the foot's long axis (the robot's heading when it landed), rad.
    pub heading: f64,
    /// Signed clearance of the foot's footprint ([`crate::world::robot::RobotParams::footprint`])
    /// to the nearest obstacle, m (negative = the foot overlaps an obstacle; a
    /// point foot's signed distance when the footprint is 0 x 0).
    pub clearance: f64,
}

/// One 1 kHz plant sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Time, s.
    pub time: f64,
    /// CoM position, m (world).
    pub position: Vector2<f64>,
    /// CoM velocity, m/s (world).
    pub velocity: Vector2<f64>,
    /// Heading, rad (accumulated).
    pub heading: f64,
    /// Turning rate in force, rad/s.
    pub turning_rate: f64,
    /// Stance side.
    pub stance_side: Side,
    /// Signed distance from the CoM to the nearest obstacle, m (negative =
    /// inside; `+inf` without obstacles; NaN unless
    /// [`SimOptions::record_clearance`]).
    pub clearance: f64,
}

/// Everything a run produced.
#[derive(Clone, Debug)]
pub struct SimResult {
    /// The scenario that ran.
    pub scenario: Scenario,
    /// The options it ran with.
    pub options: SimOptions,
    /// Why it ended.
    pub outcome: Outcome,
    /// Control cycles in order.
    pub cycles: Vec<CycleRecord>,
    /// Footsteps in order (the initial stance foot first).
    pub footsteps: Vec<Footstep>,
    /// CoM samples at 1 kHz.
    pub samples: Vec<Sample>,
    /// Planner output and subgoal progress.
    pub navigation: Navigation,
    /// LiDAR scans, one per control cycle (with `perception = "lidar"` and
    /// [`SimOptions::record_scans`]).
    pub scans: Vec<ScanRecord>,
    /// Each control cycle's QP, with its cycle index (with
    /// [`SimOptions::record_qps`]; cycles with invalid input build none).
    pub qps: Vec<(usize, ldcbf_reference::DenseProblem)>,
    /// What the scenario's disturbances did (pushes applied, foot errors,
    /// estimation errors; empty when none is configured).
    pub disturbance: DisturbanceLog,
    /// Contacts of the body and the stance foot with the true obstacles, at
    /// 1 kHz, each with who moved into whom ([`ContactCause`]; empty unless
    /// [`SimOptions::record_clearance`]).
    pub contacts: Vec<Contact>,
    /// The occupancy map, its update times and the plans made on it (with
    /// `perception = "lidar"`; [`MappingLog`]).
    pub mapping: Option<MappingLog>,
    /// Where the obstacles were at each control cycle (one entry per
    /// [`SimResult::cycles`] entry): each obstacle's vertex centre, m, world
    /// frame, in the scenario's order; empty when every obstacle is at rest.
    /// The figures draw people who react where they were, not where a
    /// constant velocity would have taken them.
    pub obstacle_centres: Vec<Vec<Vector2<f64>>>,
}

impl SimResult {
    /// Simulated time at the end, s.
    pub fn sim_time(&self) -> f64 {
        self.samples.last().map_or(0.0, |s| s.time)
    }

    /// Distance from the last CoM sample to the goal, m.
    pub fn final_distance(&self) -> f64 {
        self.samples
            .last()
            .map_or(f64::INFINITY, |s| (s.position - self.scenario.goal).norm())
    }

    /// Footsteps landed during the run (the initial stance foot not counted).
    pub fn steps(&self) -> usize {
        self.footsteps.len().saturating_sub(1)
    }
}

/// Runs the scenario to its end (see the module docs). Fails before the first
/// tick on an invalid controller configuration or LiDAR, or
/// [`SimOptions::timing_repeats`] = 0 or above [`MAX_TIMING_REPEATS`].
pub fn run(scenario: &Scenario, options: SimOptions) -> Result<SimResult, SimError> {
    if options.timing_repeats == 0 {
        return Err(SimError::NoTimingRepeats);
    }
    if options.timing_repeats > MAX_TIMING_REPEATS {
        return Err(SimError::TooManyTimingRepeats(options.timing_repeats));
    }
    match options.solver {
        Solver::Own => run_with(scenario, options, OwnSolver),
        Solver::Clarabel => run_with(scenario, options, ClarabelBackend::default()),
    }
}

/// [`run`] with the QP backend `backend`: [`closed_loop::Loop`] ticked to its
/// end.
fn run_with<B: QpBackend<NV, NC> + Clone>(
    scenario: &Scenario,
    options: SimOptions,
    backend: B,
) -> Result<SimResult, SimError> {
    let mut state = closed_loop::Loop::new(scenario, options, backend)?;
    let outcome = loop {
        // SIGINT, SIGTERM or the caller's flag: end now (sim::cancel).
        cancel::check().map_err(SimError::Cancelled)?;
        if let Some(outcome) = state.tick() {
            break outcome;
        }
    };
    Ok(state.finish(outcome))
}

#[cfg(test)]
mod tests;

mod mapping;
pub use mapping::{MappingLog, ReplanReason, ReplanRecord};
