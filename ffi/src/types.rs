//! The C types of the API (`#[repr(C)]` structs, `#[repr(u32)]` enums, the
//! side code) and their conversions from and to the Rust controller's types.
//! cbindgen reads this module through `mod types;` in `lib.rs`.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    CommandSource, Config, CycleOutput, CycleStatus, InputError, LipState, QpStatus, Side,
};

use super::checks::LastError;
use super::{LDCBF_HORIZON, LDCBF_SIDE_LEFT, LDCBF_SIDE_RIGHT, LdcbfSide};
// Named in the doc comments only (intra-doc links).
#[cfg(doc)]
use super::{
    LDCBF_CONTROLLER_ALIGN, LDCBF_MAX_ACTIVE_OBSTACLES, LDCBF_MAX_OBSTACLES, LDCBF_MAX_POINTS,
    LDCBF_MAX_VERTICES, ldcbf_config_default, ldcbf_configure, ldcbf_controller_size, ldcbf_init,
    ldcbf_last_error, ldcbf_lip_propagate, ldcbf_step,
};

/// Result of a call: `Ok` or what the caller got wrong. Values are stable.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfResult {
    /// Success.
    Ok = 0,
    /// A required pointer argument is NULL.
    NullPointer = 1,
    /// A pointer argument is not aligned for its type (`double`: 8 bytes on
    /// most targets, `uint32_t`: 4, the controller: [`LDCBF_CONTROLLER_ALIGN`]).
    Misaligned = 2,
    /// The storage given to [`ldcbf_init`] is smaller than
    /// [`ldcbf_controller_size`] bytes.
    StorageTooSmall = 3,
    /// The controller pointer does not point to a controller set up by
    /// [`ldcbf_init`] (checked with a tag word: a best-effort guard against
    /// uninitialised or overwritten storage).
    NotInitialized = 4,
    /// An input or output buffer overlaps the controller's storage.
    Overlap = 5,
    /// The configuration is invalid; [`ldcbf_last_error`] names the field.
    InvalidConfig = 6,
    /// The controller has no valid configuration yet (from
    /// [`ldcbf_lip_propagate`]; [`ldcbf_step`] instead returns `Ok` with the
    /// hold command and [`LdcbfInputError::NotConfigured`], as the Rust
    /// controller does).
    NotConfigured = 7,
    /// A scalar argument is out of its range (a side that is neither 0 nor 1,
    /// a duration that is not finite); [`ldcbf_last_error`] names it.
    InvalidArgument = 8,
    /// More than [`LDCBF_MAX_OBSTACLES`] obstacles.
    TooManyObstacles = 9,
    /// An obstacle's points do not span a convex polygon of at most
    /// [`LDCBF_MAX_VERTICES`] corners (not finite, beyond 1e6 m, fewer than 3
    /// distinct points, collinear), or it has more than [`LDCBF_MAX_POINTS`]
    /// points; [`ldcbf_last_error`] says which and why.
    InvalidObstacle = 10,
}

/// Outcome of a control cycle (the Rust controller's `CycleStatus`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfCycleStatus {
    /// The QP was solved; the command is the optimal plan's first footstep.
    Optimal = 0,
    /// The QP had no feasible point; the command comes from the priority
    /// scheme (relaxed rows) or a fallback, see [`LdcbfCycleInfo::source`].
    Infeasible = 1,
    /// The iteration budget ran out; fallback command.
    BudgetExhausted = 2,
    /// The solver met a numerical failure; fallback command.
    NumericalFailure = 3,
    /// A measured input was not finite or out of range, or the controller is
    /// not configured ([`LdcbfOutput::input_error`] says which); the command
    /// holds the last valid target with turning rate 0.
    InvalidInput = 4,
}

/// Which input was invalid when the status is [`LdcbfCycleStatus::InvalidInput`].
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfInputError {
    /// No input error (the status is not `InvalidInput`).
    None = 0,
    /// CoM position, velocity, heading or turning rate not finite or out of
    /// range (positions within 1e6 m, speed within 100 m/s, turning rate
    /// within 100 rad/s).
    State = 1,
    /// Stance foot position not finite or out of range.
    StanceFoot = 2,
    /// Time in step not finite.
    TimeInStep = 3,
    /// Goal not finite or out of range.
    Goal = 4,
    /// The controller has no valid configuration ([`ldcbf_configure`] has not
    /// succeeded yet).
    NotConfigured = 5,
    /// Obstacle velocities were given, but not one per obstacle.
    ObstacleVelocityCount = 6,
    /// The velocity of a selected obstacle is not finite or faster than
    /// 100 m/s.
    ObstacleVelocity = 7,
    /// Velocity uncertainty radii were given, but not one per obstacle (not
    /// raised by the C API, which passes one per obstacle or none).
    ObstacleVelocityRadiusCount = 8,
    /// The velocity uncertainty radius of a selected obstacle is negative,
    /// not finite or larger than 100 m/s.
    ObstacleVelocityRadius = 9,
}

/// Where the command came from (the Rust controller's `CommandSource`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfCommandSource {
    /// This cycle's optimal plan.
    Optimal = 0,
    /// Optimal plan with the gait rows relaxed (nominal QP infeasible).
    RelaxedGait = 1,
    /// Optimal plan with the safety (and gait) rows relaxed.
    RelaxedSafety = 2,
    /// The previous cycle's plan, still feasible for this cycle's rows.
    PreviousPlan = 3,
    /// The clamped capture step.
    CaptureStep = 4,
    /// Hold the last valid target (invalid input).
    Hold = 5,
}

/// Outcome of the QP solver in a cycle.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfQpStatus {
    /// The QP was not built (invalid input).
    NotBuilt = 0,
    /// Solved to optimality.
    Solved = 1,
    /// The constraint set is empty.
    Infeasible = 2,
    /// The iteration budget ran out.
    IterationLimit = 3,
    /// A non-finite number appeared, or the Hessian was not positive definite.
    NumericalError = 4,
}

/// Controller settings (the Rust `Config`), SI units. Get the defaults (the
/// paper's Table I: a point robot, no foot rows) from
/// [`ldcbf_config_default`] and override fields. Flags are `uint8_t` and must
/// be 0 or 1; [`ldcbf_configure`] rejects anything else.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfConfig {
    /// Gravity `g`, m/s^2 (> 0).
    pub gravity: f64,
    /// CoM height `H`, m (> 0).
    pub com_height: f64,
    /// Step duration `T`, s (> 0).
    pub step_duration: f64,
    /// Minimum longitudinal (body x) velocity at the end of a step, m/s.
    pub vx_min: f64,
    /// Maximum longitudinal velocity, m/s (> `vx_min`).
    pub vx_max: f64,
    /// Minimum lateral velocity times the stance sign, m/s.
    pub vy_min: f64,
    /// Maximum lateral velocity times the stance sign, m/s (>= `vy_min`).
    pub vy_max: f64,
    /// Leg reachability half-width in each body axis, m (> 0).
    pub l_max: f64,
    /// Maneuverability coefficient `alpha`, m/rad (>= 0).
    pub alpha: f64,
    /// Turning-rate bound `omega_max`, rad/s (>= 0).
    pub omega_max: f64,
    /// LDCBF decay `gamma`, in (0, 1].
    pub gamma: f64,
    /// LDCBF margin `delta`, m (>= 0).
    pub delta: f64,
    /// Obstacles within this signed distance of the predicted CoM are active, m (> 0).
    pub r_active: f64,
    /// 1: foot-clearance rows on (every footprint keeps `foot_clearance` m
    /// off each active obstacle); 0: off (the paper's QP).
    pub foot_clearance_on: u8,
    /// Foot clearance `delta_foot`, m (finite; used when `foot_clearance_on`).
    pub foot_clearance: f64,
    /// Radius of the body disk around the CoM, m (>= 0; 0 = a point CoM).
    pub body_radius: f64,
    /// Footprint length along the heading, m (>= 0; 0 = a point foot).
    pub foot_length: f64,
    /// Footprint width across the heading, m (>= 0; 0 = a point foot).
    pub foot_width: f64,
    /// Within this distance of the goal the heading is frozen, m (>= 0).
    pub heading_freeze_radius: f64,
    /// Iteration budget of one QP solve (>= 1).
    pub max_iter: u32,
    /// Iteration budget of a whole cycle (>= `max_iter`).
    pub max_iter_cycle: u32,
    /// Halvings of each bisection of the priority scheme (<= 52).
    pub relax_bisections: u32,
    /// Largest uniform relaxation of the gait rows before the safety rows are
    /// relaxed instead, m/s (>= 0).
    pub max_gait_relaxation: f64,
    /// 1: capturability bound on (see `capture_fraction`); 0: off.
    pub capture_on: u8,
    /// Capturability bound as a fraction of `|kappa| l_max`, in (0, 1] (used
    /// when `capture_on`).
    pub capture_fraction: f64,
    /// 1: warm-start the solver with the previous cycle's active rows; 0: cold.
    pub warm_start: u8,
    /// Primal feasibility tolerance of the solver, in (0, 1e-3).
    pub tol_primal: f64,
    /// 1: at an obstacle's vertex closest to the predicted CoM, the
    /// half-plane's normal is turned towards the edge normal that blocks the
    /// way to the goal least (for maps of grid cells); 0: the closest-point
    /// normal (the paper's).
    pub turn_vertex_normals: u8,
    /// 1: use the obstacles' velocity uncertainty radii
    /// ([`ldcbf_step_uncertain`](crate::ldcbf_step_uncertain)); 0: take
    /// every radius as 0 (constant-velocity prediction, no margin).
    pub velocity_margin: u8,
    /// Largest speed of a person of uncertain velocity, m/s (> 0).
    pub person_speed_max: f64,
    /// Largest acceleration of a person of uncertain velocity, m/s^2 (>= 0).
    pub person_accel_max: f64,
    /// Time over which the set a person of uncertain velocity can reach
    /// grows, s (finite, > 0; 1000 by default: the whole horizon); beyond it
    /// the set travels with the estimate.
    pub person_reach_time: f64,
}

/// The measured state and the goal of one cycle (world frame).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfInput {
    /// CoM position `{x, y}`, m.
    pub com_position: [f64; 2],
    /// CoM velocity `{vx, vy}`, m/s.
    pub com_velocity: [f64; 2],
    /// Heading (yaw), rad.
    pub heading: f64,
    /// Current turning rate (the last commanded one), rad/s.
    pub turning_rate: f64,
    /// Position of the current stance foot `{x, y}`, m.
    pub stance_foot: [f64; 2],
    /// Which foot is the stance foot: [`LDCBF_SIDE_LEFT`] or [`LDCBF_SIDE_RIGHT`].
    pub stance_side: LdcbfSide,
    /// Time already spent in the current step, s, in `[0, step_duration]`
    /// (clamped otherwise, and [`LdcbfCycleInfo::time_clamped`] set).
    pub time_in_step: f64,
    /// Goal (or current subgoal) `{x, y}`, m.
    pub goal: [f64; 2],
}

/// A LIP state (world frame).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct LdcbfLipState {
    /// CoM position `{x, y}`, m.
    pub position: [f64; 2],
    /// CoM velocity `{vx, vy}`, m/s.
    pub velocity: [f64; 2],
    /// Heading, rad.
    pub heading: f64,
}

/// The plan predicted in a cycle.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfPlan {
    /// `x_0`: predicted state at the end of the current step.
    pub x0: LdcbfLipState,
    /// `x_1 .. x_N`: predicted states at the ends of the planned steps.
    pub states: [LdcbfLipState; LDCBF_HORIZON],
    /// `f_0 .. f_{N-1}`: stance foot `{x, y}` of each planned step, m.
    pub feet: [[f64; 2]; LDCBF_HORIZON],
    /// Side of `f_0` (the current swing foot); later feet alternate.
    pub first_side: LdcbfSide,
}

/// Diagnostics of one cycle.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfCycleInfo {
    /// QP solver outcome ([`LdcbfQpStatus::NotBuilt`] on invalid input).
    pub qp_status: LdcbfQpStatus,
    /// Where the command came from.
    pub source: LdcbfCommandSource,
    /// Solver iterations (adds plus drops) of the whole cycle.
    pub iterations: u32,
    /// Size of the final active set.
    pub active_set_size: u32,
    /// Obstacles used in the QP (at most [`LDCBF_MAX_ACTIVE_OBSTACLES`]).
    pub active_obstacles: u32,
    /// 1 if more obstacles were within `r_active` than the QP holds (the
    /// farthest were left out), else 0.
    pub obstacles_truncated: u8,
    /// 1 if the predicted CoM `p_0` lies inside (or on) an obstacle, else 0.
    pub inside_obstacle: u8,
    /// 1 if `time_in_step` was outside `[0, T]` and was clamped, else 0.
    pub time_clamped: u8,
    /// 1 if warm-start rows were given to the solver, else 0.
    pub warm_started: u8,
    /// Cost `sum_k |p_k - goal|^2` of the returned plan, m^2 (NaN for `Hold`).
    pub cost: f64,
    /// Largest violation of this cycle's QP rows by the returned plan, in the
    /// rows' units (m or m/s; 0 when all hold; NaN for `Hold`).
    pub max_violation: f64,
    /// Smallest barrier value `h_j(p_0)` over the active obstacles, m
    /// (`+inf` without active obstacles).
    pub min_h0: f64,
    /// Uniform relaxation of the gait rows in the returned plan, m/s.
    pub relax_gait: f64,
    /// Uniform relaxation of the safety rows in the returned plan, m.
    pub relax_safety: f64,
    /// Uniform relaxation of the capturability bound, m/s.
    pub relax_capture: f64,
}

/// Everything one cycle returns. All command numbers are finite.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfOutput {
    /// `f_0`: where the current swing foot should land `{x, y}`, m (world).
    pub foot_target: [f64; 2],
    /// Turning rate to apply during the next step, rad/s.
    pub turning_rate: f64,
    /// Outcome of the cycle.
    pub status: LdcbfCycleStatus,
    /// Which input was invalid ([`LdcbfInputError::None`] unless `status` is
    /// [`LdcbfCycleStatus::InvalidInput`]).
    pub input_error: LdcbfInputError,
    /// The predicted plan.
    pub plan: LdcbfPlan,
    /// Diagnostics.
    pub info: LdcbfCycleInfo,
}

/// A `u8` flag as a bool: 0 or 1, else the field's name.
fn flag(v: u8, field: &'static str) -> Result<bool, LastError> {
    match v {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(LastError::Flag(field)),
    }
}

/// A side code as a [`Side`].
pub(crate) fn side(v: LdcbfSide) -> Option<Side> {
    match v {
        LDCBF_SIDE_LEFT => Some(Side::Left),
        LDCBF_SIDE_RIGHT => Some(Side::Right),
        _ => None,
    }
}

pub(crate) fn side_code(s: Side) -> LdcbfSide {
    match s {
        Side::Left => LDCBF_SIDE_LEFT,
        Side::Right => LDCBF_SIDE_RIGHT,
    }
}

pub(crate) fn xy(v: [f64; 2]) -> Vector2<f64> {
    Vector2::new(v[0], v[1])
}

pub(crate) fn arr(v: &Vector2<f64>) -> [f64; 2] {
    [v.x, v.y]
}

// ---------------------------------------------------------------------------
// Conversions

impl From<&Config> for LdcbfConfig {
    fn from(c: &Config) -> Self {
        LdcbfConfig {
            gravity: c.gravity,
            com_height: c.com_height,
            step_duration: c.step_duration,
            vx_min: c.vx_min,
            vx_max: c.vx_max,
            vy_min: c.vy_min,
            vy_max: c.vy_max,
            l_max: c.l_max,
            alpha: c.alpha,
            omega_max: c.omega_max,
            gamma: c.gamma,
            delta: c.delta,
            r_active: c.r_active,
            foot_clearance_on: u8::from(c.foot_clearance.is_some()),
            foot_clearance: c.foot_clearance.unwrap_or(0.0),
            body_radius: c.body_radius,
            foot_length: c.foot_length,
            foot_width: c.foot_width,
            heading_freeze_radius: c.heading_freeze_radius,
            max_iter: c.max_iter,
            max_iter_cycle: c.max_iter_cycle,
            relax_bisections: c.relax_bisections,
            max_gait_relaxation: c.max_gait_relaxation,
            capture_on: u8::from(c.capture_fraction.is_some()),
            capture_fraction: c.capture_fraction.unwrap_or(0.0),
            warm_start: u8::from(c.warm_start),
            tol_primal: c.tol_primal,
            turn_vertex_normals: u8::from(c.turn_vertex_normals),
            velocity_margin: u8::from(c.velocity_margin),
            person_speed_max: c.person_speed_max,
            person_accel_max: c.person_accel_max,
            person_reach_time: c.person_reach_time,
        }
    }
}

impl LdcbfConfig {
    /// The Rust configuration, or the flag that is neither 0 nor 1 (the
    /// values are validated by `Controller::configure`).
    pub(crate) fn to_config(self) -> Result<Config, LastError> {
        let foot = flag(self.foot_clearance_on, "foot_clearance_on")?;
        let capture = flag(self.capture_on, "capture_on")?;
        let warm = flag(self.warm_start, "warm_start")?;
        let turn = flag(self.turn_vertex_normals, "turn_vertex_normals")?;
        let margin = flag(self.velocity_margin, "velocity_margin")?;
        Ok(Config {
            gravity: self.gravity,
            com_height: self.com_height,
            step_duration: self.step_duration,
            vx_min: self.vx_min,
            vx_max: self.vx_max,
            vy_min: self.vy_min,
            vy_max: self.vy_max,
            l_max: self.l_max,
            alpha: self.alpha,
            omega_max: self.omega_max,
            gamma: self.gamma,
            delta: self.delta,
            r_active: self.r_active,
            foot_clearance: foot.then_some(self.foot_clearance),
            body_radius: self.body_radius,
            foot_length: self.foot_length,
            foot_width: self.foot_width,
            heading_freeze_radius: self.heading_freeze_radius,
            max_iter: self.max_iter,
            max_iter_cycle: self.max_iter_cycle,
            relax_bisections: self.relax_bisections,
            max_gait_relaxation: self.max_gait_relaxation,
            capture_fraction: capture.then_some(self.capture_fraction),
            warm_start: warm,
            tol_primal: self.tol_primal,
            turn_vertex_normals: turn,
            velocity_margin: margin,
            person_speed_max: self.person_speed_max,
            person_accel_max: self.person_accel_max,
            person_reach_time: self.person_reach_time,
        })
    }
}

impl From<&LipState> for LdcbfLipState {
    fn from(s: &LipState) -> Self {
        LdcbfLipState {
            position: arr(&s.position),
            velocity: arr(&s.velocity),
            heading: s.heading,
        }
    }
}

impl From<&CycleOutput<LDCBF_HORIZON>> for LdcbfOutput {
    fn from(o: &CycleOutput<LDCBF_HORIZON>) -> Self {
        let (status, input_error) = match o.status {
            CycleStatus::Optimal => (LdcbfCycleStatus::Optimal, LdcbfInputError::None),
            CycleStatus::Infeasible => (LdcbfCycleStatus::Infeasible, LdcbfInputError::None),
            CycleStatus::BudgetExhausted => {
                (LdcbfCycleStatus::BudgetExhausted, LdcbfInputError::None)
            }
            CycleStatus::NumericalFailure => {
                (LdcbfCycleStatus::NumericalFailure, LdcbfInputError::None)
            }
            CycleStatus::InvalidInput(e) => (
                LdcbfCycleStatus::InvalidInput,
                match e {
                    InputError::State => LdcbfInputError::State,
                    InputError::StanceFoot => LdcbfInputError::StanceFoot,
                    InputError::TimeInStep => LdcbfInputError::TimeInStep,
                    InputError::Goal => LdcbfInputError::Goal,
                    InputError::NotConfigured => LdcbfInputError::NotConfigured,
                    InputError::ObstacleVelocityCount => LdcbfInputError::ObstacleVelocityCount,
                    InputError::ObstacleVelocity => LdcbfInputError::ObstacleVelocity,
                    InputError::ObstacleVelocityRadiusCount => {
                        LdcbfInputError::ObstacleVelocityRadiusCount
                    }
                    InputError::ObstacleVelocityRadius => LdcbfInputError::ObstacleVelocityRadius,
                },
            ),
        };
        let i = &o.info;
        LdcbfOutput {
            foot_target: arr(&o.foot_target),
            turning_rate: o.turning_rate,
            status,
            input_error,
            plan: LdcbfPlan {
                x0: (&o.plan.x0).into(),
                states: o.plan.states.map(|s| (&s).into()),
                feet: o.plan.feet.map(|f| arr(&f)),
                first_side: side_code(o.plan.first_side),
            },
            info: LdcbfCycleInfo {
                qp_status: match i.qp_status {
                    None => LdcbfQpStatus::NotBuilt,
                    Some(QpStatus::Solved) => LdcbfQpStatus::Solved,
                    Some(QpStatus::Infeasible) => LdcbfQpStatus::Infeasible,
                    Some(QpStatus::IterationLimit) => LdcbfQpStatus::IterationLimit,
                    Some(QpStatus::NumericalError) => LdcbfQpStatus::NumericalError,
                },
                source: match i.source {
                    CommandSource::Optimal => LdcbfCommandSource::Optimal,
                    CommandSource::RelaxedGait => LdcbfCommandSource::RelaxedGait,
                    CommandSource::RelaxedSafety => LdcbfCommandSource::RelaxedSafety,
                    CommandSource::PreviousPlan => LdcbfCommandSource::PreviousPlan,
                    CommandSource::CaptureStep => LdcbfCommandSource::CaptureStep,
                    CommandSource::Hold => LdcbfCommandSource::Hold,
                },
                iterations: i.iterations,
                active_set_size: u32::from(i.active_set_size),
                active_obstacles: u32::from(i.active_obstacles),
                obstacles_truncated: u8::from(i.obstacles_truncated),
                inside_obstacle: u8::from(i.inside_obstacle),
                time_clamped: u8::from(i.time_clamped),
                warm_started: u8::from(i.warm_started),
                cost: i.cost,
                max_violation: i.max_violation,
                min_h0: i.min_h0,
                relax_gait: i.relax_gait,
                relax_safety: i.relax_safety,
                relax_capture: i.relax_capture,
            },
        }
    }
}
