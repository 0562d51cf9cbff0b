//! The controller: configuration, one control cycle, status and fallback commands.
//!
//! ## Sizes
//!
//! Stable Rust cannot write `2 * N` in a type, so the sizes are four const
//! parameters whose relations are checked at compile time (`const { assert!(..) }`
//! in [`Controller::configure`], which [`Controller::new`] calls):
//!
//! | parameter | meaning | rule |
//! |---|---|---|
//! | `N` | horizon (footsteps planned) | `N >= 1` |
//! | `NV` | QP variables | `NV == 2 * N` |
//! | `NC` | QP row capacity | `NC >= 8 N + N NOBS` ([`constraint_capacity`]); `8 N + 2 N NOBS` to allow foot clearance |
//! | `NOBS` | obstacle capacity (active obstacles used per cycle) | `NOBS >= 0` |
//!
//! [`PaperController`] is the paper's configuration (`N = 3`, 8 obstacles).
//! Horizons up to `N = 20` (and beyond) work: the QP is solved in the
//! well-conditioned variables `z = (p_1, .., p_N)` of [`crate::constraints`]
//! (Hessian `2 I` for every `N`), an exact reformulation of SPEC 2 item 3; the
//! command and the plan are footsteps and states in the world frame, as the
//! spec defines them.
//!
//! ## Status and commands
//!
//! Every call to [`Controller::step`] returns a finite command and says where it
//! came from ([`CommandSource`]):
//!
//! * [`CycleStatus::Optimal`]: the QP was solved; the command is `f_0` of the
//!   optimal plan and `omega_bar`.
//! * [`CycleStatus::Infeasible`]: the nominal QP has no solution. The priority
//!   scheme of [`crate::relax`] relaxes the gait rows, and if that is not enough
//!   the safety rows, by the smallest uniform amount and returns the optimal plan
//!   of that relaxed problem ([`CommandSource::RelaxedGait`],
//!   [`CommandSource::RelaxedSafety`]; the amounts are in [`CycleInfo`]). Leg
//!   reachability always holds for these commands.
//! * If the relaxation cannot finish (budget, numerical failure), and for
//!   [`CycleStatus::BudgetExhausted`] and [`CycleStatus::NumericalFailure`]: a
//!   fallback chosen from two candidates, the previous cycle's plan (shifted by
//!   one step if a step ended in between, [`CommandSource::PreviousPlan`]) and
//!   the *capture steps* ([`CommandSource::CaptureStep`]): the first that
//!   satisfies every row of this cycle's QP, else the one that keeps leg
//!   reachability with the smaller safety-row violation. The capture step: the
//!   swing foot goes to the instantaneous capture point `p_0 + v_0 / beta` clamped
//!   into the reachability box around `p_0`, and the turning rate is 0
//!   ([`CommandSource::CaptureStep`]). A capture step brings a LIP to rest over the
//!   foot; the later feet repeat the rule from the state it leads to. It honours
//!   leg reachability but not necessarily the LDCBF rows.
//! * [`CycleStatus::InvalidInput`]: a measured input was NaN or infinite, or
//!   the controller is not configured yet ([`InputError::NotConfigured`], see
//!   [`Controller::UNCONFIGURED`]). The command holds: the last valid swing
//!   target (or the stance foot, or the origin if that is not finite either)
//!   and turning rate 0 ([`CommandSource::Hold`]).
#![allow(non_snake_case)]

use nalgebra::{ArrayStorage, SVector, Vector2};

use crate::constraints::{
    Condensed, GaitBounds, HalfPlane, RowId, RowKind, push_foot_row, push_gait_rows, push_ldcbf_row,
};
use crate::geometry::{ConvexPolygon, MAX_COORDINATE, closest_point_point_polygon};
use crate::heading::{HeadingPlan, plan_heading, wrap_angle};
use crate::lip::Lip;
use crate::qp::{DenseQp, DualActiveSet, OwnSolver, QpBackend, QpSettings, QpSolution, QpStatus};
use crate::relax;

/// Row capacity needed for horizon `n`, `nobs` obstacles, with or without the
/// foot-clearance rows: `8 n + n nobs (x2 with foot clearance)`.
pub const fn constraint_capacity(n: usize, nobs: usize, foot_clearance: bool) -> usize {
    8 * n + n * nobs * if foot_clearance { 2 } else { 1 }
}

/// The paper's configuration: horizon 3, up to 8 active obstacles, no foot
/// clearance rows.
pub type PaperController = Controller<3, 6, { constraint_capacity(3, 8, false) }, 8>;

/// The paper's horizon and obstacle capacity with room for the foot-clearance
/// rows (`NC = 72`): a robot with a body and feet ([`Config::body_radius`],
/// [`Config::foot_clearance`]). The simulator runs this one.
pub type RobotController = Controller<3, 6, { constraint_capacity(3, 8, true) }, 8>;

/// Which foot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    /// Left foot (`s = -1`).
    Left,
    /// Right foot (`s = +1`).
    Right,
}

impl Side {
    /// `s`: +1 for the right foot, -1 for the left (SPEC 2.5).
    pub fn sign(self) -> f64 {
        match self {
            Side::Left => -1.0,
            Side::Right => 1.0,
        }
    }
    /// The other foot.
    pub fn opposite(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
}

/// Controller settings. Units: SI (m, s, rad). Build with `Default` (the paper's
/// Table I) and override fields; [`Config::validate`] names the first bad field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Gravity `g`, m/s^2.
    pub gravity: f64,
    /// CoM height `H`, m.
    pub com_height: f64,
    /// Step duration `T`, s.
    pub step_duration: f64,
    /// Minimum longitudinal velocity at the end of a step, m/s.
    pub vx_min: f64,
    /// Maximum longitudinal velocity, m/s.
    pub vx_max: f64,
    /// Minimum lateral velocity (times the stance sign), m/s.
    pub vy_min: f64,
    /// Maximum lateral velocity (times the stance sign), m/s.
    pub vy_max: f64,
    /// Leg reachability half-width in each body axis, m.
    pub l_max: f64,
    /// Maneuverability coefficient `alpha` (m/rad): `v_lon <= vx_max - alpha/pi |omega|`.
    pub alpha: f64,
    /// Turning-rate bound `omega_max`, rad/s.
    pub omega_max: f64,
    /// LDCBF decay `gamma` in (0, 1]; 1 gives `h(p_{k+1}) >= 0`.
    pub gamma: f64,
    /// LDCBF margin `delta` >= 0, m.
    pub delta: f64,
    /// Obstacles whose signed distance to `p_0` is at most this are active, m.
    pub r_active: f64,
    /// Foot clearance `delta_foot` (m): every footstep's footprint (the
    /// `foot_length` x `foot_width` rectangle centred on `f_k`, long side along
    /// the step's heading `theta_k`) keeps at least this distance from each
    /// active obstacle's half-plane: `eta'(f_k - c) >= delta_foot + support`,
    /// where `support` is the rectangle's extent along `eta`. `None` = off
    /// (the paper's QP). With it on, the LDCBF margin also covers the CoM's arc
    /// between step ends (see [`Config::barrier_margin`]).
    pub foot_clearance: Option<f64>,
    /// Radius of the robot's body, m (>= 0): a disk around the CoM in the
    /// horizontal plane that the barrier keeps out of every obstacle (the
    /// LDCBF margin is `body_radius + delta`, plus the arc term of
    /// [`Config::barrier_margin`]). 0 = a point CoM, as in the paper.
    pub body_radius: f64,
    /// Length of the foot's footprint along the heading, m (>= 0; 0 = a point foot).
    pub foot_length: f64,
    /// Width of the foot's footprint across the heading, m (>= 0; 0 = a point foot).
    pub foot_width: f64,
    /// Within this distance of the goal the heading is frozen (`omega_bar = 0`), m.
    pub heading_freeze_radius: f64,
    /// Iteration budget of one QP solve (adds plus drops).
    pub max_iter: u32,
    /// Iteration budget of a whole cycle, including the solves of the priority
    /// scheme for infeasible cycles (>= `max_iter`).
    pub max_iter_cycle: u32,
    /// Halvings of each bisection of the priority scheme (precision
    /// `violation / 2^relax_bisections`), at most 52.
    pub relax_bisections: u32,
    /// Largest uniform relaxation of the gait (velocity, maneuverability) rows,
    /// m/s of the bounded body-frame velocity component (each row `a'v_{k+1} <=
    /// b` becomes `a'v_{k+1} <= b + eps`), before the priority scheme relaxes
    /// the safety rows instead (see [`crate::relax`]).
    pub max_gait_relaxation: f64,
    /// Capturability bound (see [`crate::relax`]): every body-frame component of
    /// every predicted end-of-step velocity is kept within `capture_fraction
    /// |kappa| l_max` (m/s; `|kappa| l_max` = 0.976 m/s for Table I is the
    /// speed above which no step within reach can slow the LIP down), above
    /// the gait rows and below the safety rows in the priority order. A
    /// fraction in (0, 1]; `None` = off.
    pub capture_fraction: Option<f64>,
    /// Prefer the previous cycle's active rows (shifted) when choosing rows to add.
    pub warm_start: bool,
    /// Primal feasibility tolerance of the solver (on unit-norm rows), m or m/s.
    pub tol_primal: f64,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            gravity: 9.81,
            com_height: 1.0,
            step_duration: 0.4,
            vx_min: -0.1,
            vx_max: 0.8,
            vy_min: 0.1,
            vy_max: 0.4,
            l_max: 0.1 * 1.732_050_807_568_877_2,
            alpha: 1.44,
            omega_max: 0.156 * core::f64::consts::PI,
            gamma: 0.3,
            delta: 0.0,
            r_active: 4.0,
            foot_clearance: None,
            body_radius: 0.0,
            foot_length: 0.0,
            foot_width: 0.0,
            heading_freeze_radius: 0.3,
            max_iter: 64,
            max_iter_cycle: 2048,
            relax_bisections: 12,
            max_gait_relaxation: 0.1,
            capture_fraction: Some(0.92),
            warm_start: true,
            tol_primal: 1e-10,
        }
    }
}

/// A configuration error: which field, and what is wrong with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConfigError {
    /// Name of the offending field of [`Config`].
    pub field: &'static str,
    /// What the field must satisfy.
    pub requirement: &'static str,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "invalid controller setting `{}`: {}",
            self.field, self.requirement
        )
    }
}

impl core::error::Error for ConfigError {}

impl Config {
    /// All-zero placeholder of an unconfigured controller (fails
    /// [`Config::validate`]; never used to compute anything).
    const UNSET: Config = Config {
        gravity: 0.0,
        com_height: 0.0,
        step_duration: 0.0,
        vx_min: 0.0,
        vx_max: 0.0,
        vy_min: 0.0,
        vy_max: 0.0,
        l_max: 0.0,
        alpha: 0.0,
        omega_max: 0.0,
        gamma: 0.0,
        delta: 0.0,
        r_active: 0.0,
        foot_clearance: None,
        body_radius: 0.0,
        foot_length: 0.0,
        foot_width: 0.0,
        heading_freeze_radius: 0.0,
        max_iter: 0,
        max_iter_cycle: 0,
        relax_bisections: 0,
        max_gait_relaxation: 0.0,
        capture_fraction: None,
        warm_start: false,
        tol_primal: 0.0,
    };

    /// This configuration with the iteration budgets (`max_iter`,
    /// `max_iter_cycle`) multiplied by `ceil(n / 3)`, for a controller of horizon
    /// `n`. The defaults are sized for the paper's `N = 3`; the rows and the
    /// active sets grow linearly with the horizon (closed loops on the shipped
    /// layouts needed at most 112 iterations per cycle at `N = 10` and 326 at
    /// `N = 20`, `tests/horizon.rs`). Saturates instead of overflowing.
    pub fn with_budgets_for_horizon(self, n: usize) -> Config {
        let scale = u32::try_from(n.div_ceil(3)).unwrap_or(u32::MAX).max(1);
        Config {
            max_iter: self.max_iter.saturating_mul(scale),
            max_iter_cycle: self.max_iter_cycle.saturating_mul(scale),
            ..self
        }
    }

    /// The names of every field, in declaration order (for hosts that read or
    /// set them by name: the scenario files, the Python package).
    pub const FIELDS: [&'static str; 25] = [
        "gravity",
        "com_height",
        "step_duration",
        "vx_min",
        "vx_max",
        "vy_min",
        "vy_max",
        "l_max",
        "alpha",
        "omega_max",
        "gamma",
        "delta",
        "r_active",
        "foot_clearance",
        "body_radius",
        "foot_length",
        "foot_width",
        "heading_freeze_radius",
        "max_iter",
        "max_iter_cycle",
        "relax_bisections",
        "max_gait_relaxation",
        "capture_fraction",
        "warm_start",
        "tol_primal",
    ];

    /// The margin of the step-end LDCBF rows, m: `h(p) = eta'(p - c) - margin`.
    ///
    /// `body_radius + delta` keeps the body disk `delta` clear of each
    /// obstacle's half-plane at the step ends. With foot clearance on, it also
    /// covers the CoM's continuous arc between step ends: during step `k` the
    /// LIP gives, for `t` in `[0, T]`,
    ///
    /// ```text
    /// e(p(t)) = (1 - w0 - wT) e(f_k) + w0 e(p_k) + wT e(p_{k+1}),
    /// w0 = sinh(beta (T - t)) / sinh(beta T),  wT = sinh(beta t) / sinh(beta T),
    /// ```
    ///
    /// with `e(p) = eta'(p - c)` (each axis of `p - f_k` solves `y'' = beta^2 y`
    /// with the step-end values as boundary conditions). The weights are
    /// `>= 0` and `w0 + wT >= 1 / cosh(beta T / 2)` (at `t = T / 2`), so `e`
    /// along the arc is a convex combination of the two step-end values and
    /// the stance foot's. With the foot rows keeping `e(f_k) >= F`, where
    /// `F = foot_clearance + min(foot_length, foot_width) / 2`, and the step-end rows keeping
    /// `e(p_k) >= body_radius + delta + mu`, the arc keeps
    /// `e(p(t)) >= body_radius + delta` for every `t` when
    /// `mu = (cosh(beta T / 2) - 1) max(0, body_radius + delta - F)`: that is the
    /// term added here. Without foot rows only the step ends are guaranteed.
    pub fn barrier_margin(&self) -> f64 {
        let body = self.body_radius + self.delta;
        match self.foot_clearance {
            None => body,
            Some(df) => {
                let foot = df + 0.5 * self.foot_length.min(self.foot_width);
                let beta = crate::float::sqrt(self.gravity / self.com_height);
                let bulge = libm::cosh(0.5 * beta * self.step_duration) - 1.0;
                body + bulge * (body - foot).max(0.0)
            }
        }
    }

    /// The margin of a foot-clearance row, m: `foot_clearance` (0 when off) plus
    /// the extent along the unit normal `eta` (world frame) of the foot's
    /// footprint, a `foot_length` x `foot_width` rectangle whose long axis is
    /// the heading `theta` (rad).
    pub fn foot_margin(&self, eta: &Vector2<f64>, theta: f64) -> f64 {
        let (s, c) = libm::sincos(theta);
        let along = (eta.x * c + eta.y * s).abs();
        let across = (-eta.x * s + eta.y * c).abs();
        self.foot_clearance.unwrap_or(0.0)
            + 0.5 * (self.foot_length * along + self.foot_width * across)
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let err = |field, requirement| Err(ConfigError { field, requirement });
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.gravity) {
            return err("gravity", "must be finite and > 0");
        }
        if !pos(self.com_height) {
            return err("com_height", "must be finite and > 0");
        }
        if !pos(self.step_duration) {
            return err("step_duration", "must be finite and > 0");
        }
        if !self.vx_min.is_finite() {
            return err("vx_min", "must be finite");
        }
        if !(self.vx_max.is_finite() && self.vx_max > self.vx_min) {
            return err("vx_max", "must be finite and > vx_min");
        }
        if !self.vy_min.is_finite() {
            return err("vy_min", "must be finite");
        }
        if !(self.vy_max.is_finite() && self.vy_max >= self.vy_min) {
            return err("vy_max", "must be finite and >= vy_min");
        }
        if !pos(self.l_max) {
            return err("l_max", "must be finite and > 0");
        }
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return err("alpha", "must be finite and >= 0");
        }
        if !(self.omega_max.is_finite() && self.omega_max >= 0.0) {
            return err("omega_max", "must be finite and >= 0");
        }
        if !(self.gamma.is_finite() && self.gamma > 0.0 && self.gamma <= 1.0) {
            return err("gamma", "must be in (0, 1]");
        }
        if !(self.delta.is_finite() && self.delta >= 0.0) {
            return err("delta", "must be finite and >= 0");
        }
        if !pos(self.r_active) {
            return err("r_active", "must be finite and > 0");
        }
        if let Some(d) = self.foot_clearance
            && !d.is_finite()
        {
            return err("foot_clearance", "must be finite when set");
        }
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
        if !nonneg(self.body_radius) {
            return err("body_radius", "must be finite and >= 0");
        }
        if !nonneg(self.foot_length) {
            return err("foot_length", "must be finite and >= 0");
        }
        if !nonneg(self.foot_width) {
            return err("foot_width", "must be finite and >= 0");
        }
        if !(self.heading_freeze_radius.is_finite() && self.heading_freeze_radius >= 0.0) {
            return err("heading_freeze_radius", "must be finite and >= 0");
        }
        if self.max_iter == 0 {
            return err("max_iter", "must be >= 1");
        }
        if self.max_iter_cycle < self.max_iter {
            return err("max_iter_cycle", "must be >= max_iter");
        }
        if self.relax_bisections > 52 {
            return err("relax_bisections", "must be <= 52");
        }
        if !(self.max_gait_relaxation.is_finite() && self.max_gait_relaxation >= 0.0) {
            return err("max_gait_relaxation", "must be finite and >= 0");
        }
        if let Some(r) = self.capture_fraction
            && !(r.is_finite() && r > 0.0 && r <= 1.0)
        {
            return err("capture_fraction", "must be in (0, 1] when set");
        }
        if !(self.tol_primal.is_finite() && self.tol_primal > 0.0 && self.tol_primal < 1e-3) {
            return err("tol_primal", "must be in (0, 1e-3)");
        }
        Ok(())
    }
}

/// The measured state and context of one control cycle. World frame W.
#[derive(Clone, Copy, Debug)]
pub struct CycleInput<'a, const V: usize> {
    /// CoM position, m.
    pub com_position: Vector2<f64>,
    /// CoM velocity, m/s.
    pub com_velocity: Vector2<f64>,
    /// Heading (yaw), rad.
    pub heading: f64,
    /// Current turning rate (the last commanded `omega`), rad/s.
    pub turning_rate: f64,
    /// Position of the current stance foot, m.
    pub stance_foot: Vector2<f64>,
    /// Which foot is the stance foot.
    pub stance_side: Side,
    /// Time already spent in the current step, s, in `[0, T]` (clamped otherwise).
    pub time_in_step: f64,
    /// Goal or current subgoal, m.
    pub goal: Vector2<f64>,
    /// Obstacles (validated convex polygons, world frame).
    pub obstacles: &'a [ConvexPolygon<V>],
}

/// The disk, world frame W, that holds every obstacle a cycle can select:
/// [`Controller::obstacle_query`] for a caller that keeps its map in a spatial
/// index and passes only the candidates to [`Controller::step_among`].
///
/// A cycle selects obstacle `j` only if `closest_point_point_polygon(center,
/// P_j).signed_distance <= radius` (`center` is the cycle's `p_0`, `radius` is
/// [`Config::r_active`]). Such a polygon has a point within `radius` of
/// `center` (its closest point, or `center` itself when inside), so its
/// axis-aligned bounding box is within `radius` of `center` too: an index
/// query for the boxes within [`ObstacleQuery::padded_radius`] of `center`
/// returns every obstacle the cycle can select (the padding covers the
/// rounding of both distance computations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleQuery {
    /// The cycle's `p_0`, the predicted CoM position at the end of the current
    /// step, m (world frame W): exactly the point the selection measures from.
    pub center: Vector2<f64>,
    /// [`Config::r_active`], m.
    pub radius: f64,
}

impl ObstacleQuery {
    /// `radius` plus a margin for rounding, m: `radius (1 + 1e-9) + 1e-9 (1 +
    /// |center|_inf)`, i.e. about 1e-7 m for a centre 100 m from the origin.
    /// The controller's signed distance and an index's box distance are each
    /// within a few units in the last place of the true distance (relative
    /// error about 1e-15 for coordinates up to 1e6 m), far inside this margin,
    /// so a box within the true `radius` is always within `padded_radius` as
    /// computed. A larger query only passes a few more candidates, which the
    /// controller tests exactly.
    pub fn padded_radius(&self) -> f64 {
        let scale = 1.0 + self.center.x.abs().max(self.center.y.abs());
        self.radius * (1.0 + 1e-9) + 1e-9 * scale
    }
}

/// Largest accepted CoM speed (m/s) and turning rate (rad/s): far beyond any
/// walking robot; larger values are treated as corrupted measurements.
pub const MAX_RATE: f64 = 100.0;

/// Which input was not finite or out of its physical range (positions within
/// [`crate::geometry::MAX_COORDINATE`], speed and turning rate within
/// [`MAX_RATE`], heading within `MAX_COORDINATE` rad).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputError {
    /// CoM position, velocity, heading or turning rate.
    State,
    /// Stance foot position.
    StanceFoot,
    /// Time in step.
    TimeInStep,
    /// Goal.
    Goal,
    /// Not a measurement: the controller has no valid configuration yet (it
    /// is [`Controller::UNCONFIGURED`] and no [`Controller::configure`] has
    /// succeeded).
    NotConfigured,
}

impl core::fmt::Display for InputError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            InputError::State => "CoM state, heading or turning rate is not finite or out of range",
            InputError::StanceFoot => "stance foot position is not finite or out of range",
            InputError::TimeInStep => "time in step is not finite",
            InputError::Goal => "goal is not finite or out of range",
            InputError::NotConfigured => "the controller is not configured",
        })
    }
}

impl core::error::Error for InputError {}

/// Outcome of a cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CycleStatus {
    /// QP solved; optimal command.
    Optimal,
    /// The QP has no feasible point; fallback command.
    Infeasible,
    /// The iteration budget ran out; fallback command.
    BudgetExhausted,
    /// The solver met a numerical failure; fallback command.
    NumericalFailure,
    /// An input was not finite or out of range, or the controller is not
    /// configured ([`InputError::NotConfigured`]); hold command.
    InvalidInput(InputError),
}

impl CycleStatus {
    /// True for [`CycleStatus::Optimal`].
    pub fn is_optimal(self) -> bool {
        matches!(self, CycleStatus::Optimal)
    }
    /// Short lower-case name, for logs.
    pub fn name(self) -> &'static str {
        match self {
            CycleStatus::Optimal => "optimal",
            CycleStatus::Infeasible => "infeasible",
            CycleStatus::BudgetExhausted => "budget_exhausted",
            CycleStatus::NumericalFailure => "numerical_failure",
            CycleStatus::InvalidInput(_) => "invalid_input",
        }
    }
}

/// Where the returned command came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandSource {
    /// This cycle's optimal plan.
    Optimal,
    /// Optimal plan with the gait rows relaxed (nominal QP infeasible).
    RelaxedGait,
    /// Optimal plan with the safety (and gait) rows relaxed: even reachability and
    /// safety together were infeasible.
    RelaxedSafety,
    /// The previous cycle's plan, still feasible for this cycle's rows.
    PreviousPlan,
    /// The clamped capture step (see module docs).
    CaptureStep,
    /// Hold the last valid target (invalid input).
    Hold,
}

impl CommandSource {
    /// Short lower-case name, for logs.
    pub fn name(self) -> &'static str {
        match self {
            CommandSource::Optimal => "optimal",
            CommandSource::RelaxedGait => "relaxed_gait",
            CommandSource::RelaxedSafety => "relaxed_safety",
            CommandSource::PreviousPlan => "previous_plan",
            CommandSource::CaptureStep => "capture_step",
            CommandSource::Hold => "hold",
        }
    }
}

/// A LIP state in the world frame.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct LipState {
    /// CoM position, m.
    pub position: Vector2<f64>,
    /// CoM velocity, m/s.
    pub velocity: Vector2<f64>,
    /// Heading, rad.
    pub heading: f64,
}

/// The predicted plan of a cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan<const N: usize> {
    /// `x_0`: predicted state at the end of the current step.
    pub x0: LipState,
    /// `x_1 .. x_N`.
    pub states: [LipState; N],
    /// `f_0 .. f_{N-1}`: stance foot of each planned step, m.
    pub feet: [Vector2<f64>; N],
    /// Side of `f_0` (the current swing foot); later feet alternate.
    pub first_side: Side,
}

/// Diagnostics of one cycle (`Copy`, for logs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleInfo {
    /// QP solver outcome, `None` when the QP was not built (invalid input).
    pub qp_status: Option<QpStatus>,
    /// Solver iterations (adds plus drops) of the whole cycle, relaxation included.
    pub iterations: u32,
    /// Size of the final active set.
    pub active_set_size: u8,
    /// Obstacles used in the QP.
    pub active_obstacles: u8,
    /// More obstacles were within `r_active` than the capacity `NOBS` (the farthest
    /// were left out).
    pub obstacles_truncated: bool,
    /// `p_0` lies inside (or on) an obstacle.
    pub inside_obstacle: bool,
    /// `time_in_step` was outside `[0, T]` and was clamped.
    pub time_clamped: bool,
    /// Some marked (warm-start) rows were given to the solver.
    pub warm_started: bool,
    /// Where the command came from.
    pub source: CommandSource,
    /// Cost `sum_k |p_k - g|^2` of the returned plan (m^2); NaN for `Hold`.
    pub cost: f64,
    /// Largest violation of this cycle's QP rows by the returned plan, in the
    /// rows' physical units (m for reachability rows, m of `h` for safety rows,
    /// m/s for gait rows; 0 when all hold; the same units as `relax_gait` and
    /// `relax_safety`); NaN for `Hold`.
    pub max_violation: f64,
    /// Smallest `h_j(p_0)` over the active obstacles (m, with the margin
    /// [`Config::barrier_margin`]), `+inf` if none.
    pub min_h0: f64,
    /// Uniform relaxation of the gait rows in the returned plan, m/s of the
    /// bounded body-frame velocity component (0 if none).
    pub relax_gait: f64,
    /// Uniform relaxation of the safety rows in the returned plan, m of `h`
    /// (0 if none).
    pub relax_safety: f64,
    /// Uniform relaxation of the capturability bound in the returned plan, m/s
    /// (0 if none or off; see [`Config::capture_fraction`]).
    pub relax_capture: f64,
}

/// Everything one cycle returns. All numbers are finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleOutput<const N: usize> {
    /// `f_0`: where the current swing foot should land, m (world).
    pub foot_target: Vector2<f64>,
    /// Turning rate to apply during the next step, rad/s.
    pub turning_rate: f64,
    /// Predicted plan.
    pub plan: Plan<N>,
    /// Outcome.
    pub status: CycleStatus,
    /// Diagnostics.
    pub info: CycleInfo,
}

/// An obstacle used in this cycle's QP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ActiveObstacle {
    /// Index in the caller's obstacle slice [`CycleInput::obstacles`] (also
    /// with [`Controller::step_among`], whose candidates are such indices).
    pub index: u32,
    /// Signed distance from `p_0`, m.
    pub distance: f64,
    /// The LDCBF half-plane.
    pub half_plane: HalfPlane,
}

/// The quantities fixed before the QP: prediction and heading plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction<const N: usize> {
    /// Predicted CoM position at the end of the current step, m.
    pub p0: Vector2<f64>,
    /// Predicted CoM velocity at the end of the current step, m/s.
    pub v0: Vector2<f64>,
    /// Heading plan (theta_0 = predicted heading at the end of the current step).
    pub heading: HeadingPlan<N>,
    /// Side of `f_0`.
    pub first_side: Side,
    /// Goal used, m.
    pub goal: Vector2<f64>,
}

impl<const N: usize> Prediction<N> {
    /// The plan from this prediction's `x_0` (start of step 0) through the
    /// predicted end-of-step `states`, with the footsteps `feet` (m, world).
    fn plan(&self, states: [LipState; N], feet: [Vector2<f64>; N]) -> Plan<N> {
        Plan {
            x0: LipState {
                position: self.p0,
                velocity: self.v0,
                heading: self.heading.theta[0],
            },
            states,
            feet,
            first_side: self.first_side,
        }
    }
}

/// One cycle's QP and its bookkeeping, as assembled by [`Controller::assemble`].
/// Public so that the reference crate can solve exactly the same problem.
#[derive(Clone, Debug)]
pub struct Assembly<const N: usize, const NV: usize, const NC: usize, const NOBS: usize> {
    /// The QP: `min 1/2 z'Hz + q'z, G z <= h` (H from [`Controller::solver`]) in
    /// the variables `z = (p_1, .., p_N)` of [`crate::constraints`];
    /// [`Controller::feet_of`] gives the footsteps of a solution.
    pub qp: DenseQp<NV, NC>,
    /// Constant of the cost: cost = `1/2 z'Hz + q'z + cost_constant`.
    pub cost_constant: f64,
    /// Identity of each row.
    pub rows: [RowId; NC],
    /// Prediction and headings.
    pub prediction: Prediction<N>,
    /// Active obstacles, nearest first (first `n_obstacles` valid).
    pub obstacles: [ActiveObstacle; NOBS],
    /// Number of active obstacles.
    pub n_obstacles: usize,
    /// See [`CycleInfo::obstacles_truncated`].
    pub obstacles_truncated: bool,
    /// See [`CycleInfo::time_clamped`].
    pub time_clamped: bool,
}

impl<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>
    Assembly<N, NV, NC, NOBS>
{
    /// An empty assembly (no rows, no obstacles), all storage zero: usable in
    /// `const` and `static` initialisers (a `static` holding it lands in `.bss`).
    pub const EMPTY: Self = Assembly {
        qp: DenseQp::EMPTY,
        cost_constant: 0.0,
        rows: [RowId::DEFAULT; NC],
        prediction: Prediction {
            p0: Vector2::new(0.0, 0.0),
            v0: Vector2::new(0.0, 0.0),
            heading: HeadingPlan {
                omega_bar: 0.0,
                theta: [0.0; N],
                theta_end: 0.0,
            },
            first_side: Side::Left,
            goal: Vector2::new(0.0, 0.0),
        },
        obstacles: [ActiveObstacle::ZERO; NOBS],
        n_obstacles: 0,
        obstacles_truncated: false,
        time_clamped: false,
    };

    /// Resets every field in place to [`Assembly::EMPTY`] (no temporary copy
    /// of the whole assembly).
    fn clear_in_place(&mut self) {
        clear_qp_in_place(&mut self.qp);
        self.cost_constant = 0.0;
        self.rows.fill(RowId::DEFAULT);
        let pred = &mut self.prediction;
        pred.p0 = Vector2::zeros();
        pred.v0 = Vector2::zeros();
        pred.heading.omega_bar = 0.0;
        pred.heading.theta.fill(0.0);
        pred.heading.theta_end = 0.0;
        pred.first_side = Side::Left;
        pred.goal = Vector2::zeros();
        self.obstacles.fill(ActiveObstacle::ZERO);
        self.n_obstacles = 0;
        self.obstacles_truncated = false;
        self.time_clamped = false;
    }

    /// The active obstacles, nearest first.
    pub fn active_obstacles(&self) -> &[ActiveObstacle] {
        &self.obstacles[..self.n_obstacles.min(NOBS)]
    }
}

impl<const N: usize, const NV: usize, const NC: usize, const NOBS: usize> Default
    for Assembly<N, NV, NC, NOBS>
{
    /// [`Assembly::EMPTY`].
    fn default() -> Self {
        Self::EMPTY
    }
}

impl ActiveObstacle {
    /// All-zero placeholder (index 0, distance 0, zero half-plane).
    const ZERO: ActiveObstacle = ActiveObstacle {
        index: 0,
        distance: 0.0,
        half_plane: HalfPlane {
            c: Vector2::new(0.0, 0.0),
            eta: Vector2::new(0.0, 0.0),
        },
    };
}

/// Empties `qp` in place: no rows, `q`, `G` and `h` zero.
fn clear_qp_in_place<const NV: usize, const NC: usize>(qp: &mut DenseQp<NV, NC>) {
    qp.clear();
    qp.gt.fill(0.0);
    qp.h.fill(0.0);
}

/// Warm-start and fallback memory carried from one cycle to the next.
#[derive(Clone, Copy, Debug)]
struct Memory<const NV: usize> {
    /// Active rows of the last solved QP.
    active: [RowId; NV],
    n_active: usize,
    /// Last planned footsteps `f_0 .. f_{N-1}` (interleaved, m, world; not the QP
    /// variables, which depend on the cycle's `x_0`), valid when `has_plan`.
    plan: SVector<f64, NV>,
    has_plan: bool,
    /// Stance side when that plan was made.
    stance: Side,
    /// Last valid swing target, for `Hold`.
    last_target: Option<Vector2<f64>>,
}

/// The LDCBF-MPC controller: precomputed model and factored Hessian, plus the
/// warm-start memory. One [`Controller::step`] per control cycle.
///
/// Build it with [`Controller::new`], or, without the controller ever being
/// on the stack (embedded targets), as [`Controller::UNCONFIGURED`] in a
/// `static` (all storage zero: `.bss`, no flash) followed by
/// [`Controller::configure`] in place.
#[derive(Clone, Debug)]
pub struct Controller<const N: usize, const NV: usize, const NC: usize, const NOBS: usize> {
    core: Core<N, NV, NC>,
    memory: Memory<NV>,
    work: Assembly<N, NV, NC, NOBS>,
}

/// The immutable, precomputed part of the controller.
#[derive(Clone, Debug)]
struct Core<const N: usize, const NV: usize, const NC: usize> {
    /// `config`, `lip`, `model` and `solver` hold a validated configuration
    /// (else they are the all-zero placeholders and every step holds).
    configured: bool,
    config: Config,
    /// [`Config::barrier_margin`], m (computed once at configure).
    barrier_margin: f64,
    lip: Lip,
    model: Condensed<N>,
    solver: DualActiveSet<NV, NC>,
}

impl<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>
    Controller<N, NV, NC, NOBS>
{
    /// A controller without a configuration, all storage zero (so a `static`
    /// initialised with it lands in `.bss` and costs no flash). Until
    /// [`Controller::configure`] succeeds, [`Controller::step`] returns
    /// [`CycleStatus::InvalidInput`]`(`[`InputError::NotConfigured`]`)` with the
    /// hold command ([`CommandSource::Hold`]: the stance foot, or the origin if
    /// that is not finite, and turning rate 0), and [`Controller::assemble`]
    /// returns `Err(InputError::NotConfigured)`; [`Controller::config`],
    /// [`Controller::lip`], [`Controller::model`] and [`Controller::solver`]
    /// return all-zero placeholders.
    pub const UNCONFIGURED: Self = Controller {
        core: Core {
            configured: false,
            config: Config::UNSET,
            barrier_margin: 0.0,
            lip: Lip::ZERO,
            model: Condensed::ZERO,
            solver: DualActiveSet::PLACEHOLDER,
        },
        memory: Memory {
            active: [RowId::DEFAULT; NV],
            n_active: 0,
            plan: SVector::from_array_storage(ArrayStorage([[0.0; NV]; 1])),
            has_plan: false,
            stance: Side::Left,
            last_target: None,
        },
        work: Assembly::EMPTY,
    };

    /// Validates `config` and precomputes the model and the Hessian
    /// factorisation: [`Controller::UNCONFIGURED`] followed by
    /// [`Controller::configure`].
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        let mut controller = Self::UNCONFIGURED;
        controller.configure(config)?;
        Ok(controller)
    }

    /// Validates `config`, precomputes the model and the Hessian factorisation
    /// and writes them into `self` in place (no copy of the whole controller
    /// is made, so this is how an embedded target configures a controller held
    /// in a `static`). On success the controller is as [`Controller::new`]
    /// would build it: the warm-start and fallback memory and the workspaces
    /// are cleared. On error nothing changes (an unconfigured controller stays
    /// unconfigured, a configured one keeps its configuration and memory).
    pub fn configure(&mut self, config: Config) -> Result<(), ConfigError> {
        const {
            assert!(N >= 1, "horizon N must be >= 1");
            assert!(NV == 2 * N, "NV must equal 2 * N");
            assert!(NC >= 8 * N + N * NOBS, "NC must be >= 8 N + N NOBS");
            assert!(N < 256 && NOBS < 256 && NV < 256);
        }
        config.validate()?;
        if config.foot_clearance.is_some() && NC < constraint_capacity(N, NOBS, true) {
            return Err(ConfigError {
                field: "foot_clearance",
                requirement: "needs row capacity NC >= 8 N + 2 N NOBS",
            });
        }
        let lip = Lip::new(config.gravity, config.com_height, config.step_duration);
        let model = Condensed::<N>::new(&lip);
        // The QP's variables need the step map to be invertible for the foot:
        // `1 - cosh(beta T)` away from 0 (and everything finite). Rejects
        // `beta T < 1.4e-3` (sub-millisecond steps) and overflowing `cosh`.
        let c_minus_1 = lip.cosh_bt - 1.0;
        if !(c_minus_1 >= 1e-6 && lip.cosh_bt.is_finite() && model.kappa.is_finite()) {
            return Err(ConfigError {
                field: "step_duration",
                requirement: "gives a step map that cannot be inverted for the foot (beta T must be in [1.4e-3, 700])",
            });
        }
        let barrier_margin = config.barrier_margin();
        if !barrier_margin.is_finite() {
            return Err(ConfigError {
                field: "body_radius",
                requirement: "gives a barrier margin that is not finite",
            });
        }
        let settings = QpSettings {
            tol_primal: config.tol_primal,
            ..QpSettings::default()
        };
        let solver = DualActiveSet::new(&model.hessian::<NV>(), settings).map_err(|_| ConfigError {
            field: "com_height",
            requirement: "gives a Hessian that is not positive definite (check gravity, com_height, step_duration)",
        })?;
        // Everything is checked: commit, field by field.
        let core = &mut self.core;
        core.config = config;
        core.barrier_margin = barrier_margin;
        core.lip = lip;
        core.model = model;
        core.solver = solver;
        core.configured = true;
        let memory = &mut self.memory;
        memory.active.fill(RowId::DEFAULT);
        memory.n_active = 0;
        memory.plan.fill(0.0);
        memory.has_plan = false;
        memory.stance = Side::Left;
        memory.last_target = None;
        self.work.clear_in_place();
        Ok(())
    }

    /// True once a [`Controller::configure`] (or [`Controller::new`]) has
    /// succeeded.
    pub fn is_configured(&self) -> bool {
        self.core.configured
    }

    /// The validated configuration.
    pub fn config(&self) -> &Config {
        &self.core.config
    }

    /// The LIP model.
    pub fn lip(&self) -> &Lip {
        &self.core.lip
    }

    /// The condensed model: predictions, feet and rows as affine maps of the QP
    /// variables.
    pub fn model(&self) -> &Condensed<N> {
        &self.core.model
    }

    /// The QP solver (holds the constant Hessian `H`).
    pub fn solver(&self) -> &DualActiveSet<NV, NC> {
        &self.core.solver
    }

    /// The QP's decision vector `z = (p_1, .., p_N)` (interleaved, m, world) of a
    /// plan: its predicted positions. For the plan of an optimal or relaxed cycle
    /// this is exactly the solution of that cycle's QP; use it to evaluate the
    /// rows of [`Controller::last_assembly`] at a returned plan.
    pub fn variables_of(&self, plan: &Plan<N>) -> SVector<f64, NV> {
        let mut z = SVector::<f64, NV>::zeros();
        for (k, s) in plan.states.iter().enumerate() {
            z[2 * k] = s.position.x;
            z[2 * k + 1] = s.position.y;
        }
        z
    }

    /// The footsteps `f_0 .. f_{N-1}` (m, world) of a decision vector `z` of the
    /// QP assembled with `prediction` (inverse map of [`crate::constraints`]).
    pub fn feet_of(&self, prediction: &Prediction<N>, z: &SVector<f64, NV>) -> [Vector2<f64>; N] {
        self.core
            .model
            .feet_from_variables(&prediction.p0, &prediction.v0, z)
            .0
    }

    /// The assembly of the last `step` (its QP, rows and obstacles).
    pub fn last_assembly(&self) -> &Assembly<N, NV, NC, NOBS> {
        &self.work
    }

    /// Forgets the warm-start and fallback memory (e.g. after a restart).
    pub fn reset(&mut self) {
        self.memory.n_active = 0;
        self.memory.has_plan = false;
        self.memory.last_target = None;
    }

    /// Steps 1-2 and 5 of SPEC section 2: prediction, headings, obstacle selection
    /// and all QP rows, written into `out`. Pure: uses no warm-start memory.
    /// `Err(InputError::NotConfigured)` (and `out` unchanged) on an
    /// unconfigured controller.
    pub fn assemble<const V: usize>(
        &self,
        input: &CycleInput<'_, V>,
        out: &mut Assembly<N, NV, NC, NOBS>,
    ) -> Result<(), InputError> {
        self.core
            .assemble(input, input.obstacles.iter().enumerate(), out)
    }

    /// One control cycle (SPEC section 2): predict, plan headings, assemble and
    /// solve the QP, and return the command. Never panics on any input; the
    /// command is always finite (see the module docs for the fallbacks).
    pub fn step<const V: usize>(&mut self, input: &CycleInput<'_, V>) -> CycleOutput<N> {
        self.step_with(input, &mut OwnSolver)
    }

    /// [`Controller::step`] with another QP solver (for the reference closed loop).
    pub fn step_with<const V: usize, B: QpBackend<NV, NC>>(
        &mut self,
        input: &CycleInput<'_, V>,
        backend: &mut B,
    ) -> CycleOutput<N> {
        let Controller { core, memory, work } = self;
        match core.assemble(input, input.obstacles.iter().enumerate(), work) {
            Ok(()) => core.solve_assembled(memory, input, work, backend),
            Err(e) => hold(memory, input, e),
        }
    }

    /// Where this cycle will look for obstacles: its `p_0` (the CoM predicted
    /// at the end of the current step, computed exactly as [`Controller::step`]
    /// computes it) and [`Config::r_active`]. For a caller whose map is too
    /// large to scan every cycle: query a spatial index with it, then call
    /// [`Controller::step_among`] with the result. `Err` when `step` would
    /// reject the input (the obstacles do not matter then). Costs one LIP
    /// propagation; reads no obstacle.
    pub fn obstacle_query<const V: usize>(
        &self,
        input: &CycleInput<'_, V>,
    ) -> Result<ObstacleQuery, InputError> {
        let mut time_clamped = false;
        let (p0, _, _) = self.core.end_of_step(input, &mut time_clamped)?;
        Ok(ObstacleQuery {
            center: p0,
            radius: self.core.config.r_active,
        })
    }

    /// [`Controller::step`] considering only the obstacles
    /// `input.obstacles[i]` for `i` in `candidates`, in the candidates' order;
    /// entries out of range are skipped. The output is bit for bit that of
    /// `step` on the whole slice when `candidates` is in increasing order and
    /// holds every obstacle within [`ObstacleQuery::radius`] of
    /// [`ObstacleQuery::center`] ([`Controller::obstacle_query`]; a superset is
    /// fine): `step` skips every other obstacle without side effect, keeps the
    /// rest in slice order (nearer first, ties in slice order), and identifies
    /// them (in [`ActiveObstacle::index`], the row ids and so the warm start) by
    /// their index in `input.obstacles`, which is unchanged. The cost is that
    /// of the candidates only, whatever the length of `input.obstacles`.
    pub fn step_among<const V: usize>(
        &mut self,
        input: &CycleInput<'_, V>,
        candidates: &[u32],
    ) -> CycleOutput<N> {
        self.step_among_with(input, candidates, &mut OwnSolver)
    }

    /// [`Controller::step_among`] with another QP solver.
    pub fn step_among_with<const V: usize, B: QpBackend<NV, NC>>(
        &mut self,
        input: &CycleInput<'_, V>,
        candidates: &[u32],
        backend: &mut B,
    ) -> CycleOutput<N> {
        let Controller { core, memory, work } = self;
        match core.assemble(input, among(input.obstacles, candidates), work) {
            Ok(()) => core.solve_assembled(memory, input, work, backend),
            Err(e) => hold(memory, input, e),
        }
    }

    /// [`Controller::assemble`] considering only the `candidates`, as
    /// [`Controller::step_among`] does.
    pub fn assemble_among<const V: usize>(
        &self,
        input: &CycleInput<'_, V>,
        candidates: &[u32],
        out: &mut Assembly<N, NV, NC, NOBS>,
    ) -> Result<(), InputError> {
        self.core
            .assemble(input, among(input.obstacles, candidates), out)
    }
}

/// `(index, obstacle)` for each in-range index of `candidates`, in order.
fn among<'a, const V: usize>(
    obstacles: &'a [ConvexPolygon<V>],
    candidates: &'a [u32],
) -> impl Iterator<Item = (usize, &'a ConvexPolygon<V>)> + 'a {
    candidates.iter().filter_map(move |&i| {
        let i = i as usize;
        obstacles.get(i).map(|p| (i, p))
    })
}

impl<const N: usize, const NV: usize, const NC: usize> Core<N, NV, NC> {
    /// Validates the measured input and predicts `(p_0, v_0, tau)`: the CoM
    /// state at the end of the current step (step 1 of SPEC section 2) and the
    /// time left until then, s. Sets `time_clamped` once the time in step is
    /// known to be finite.
    fn end_of_step<const V: usize>(
        &self,
        input: &CycleInput<'_, V>,
        time_clamped: &mut bool,
    ) -> Result<(Vector2<f64>, Vector2<f64>, f64), InputError> {
        if !self.configured {
            return Err(InputError::NotConfigured);
        }
        let cfg = &self.config;
        let finite2 = |v: &Vector2<f64>| v.x.is_finite() && v.y.is_finite();
        // `!(x <= bound)` is also true for NaN.
        let within = |v: f64, bound: f64| v.abs() <= bound;
        let pos_ok = |v: &Vector2<f64>| within(v.x, MAX_COORDINATE) && within(v.y, MAX_COORDINATE);
        if !(pos_ok(&input.com_position)
            && within(
                crate::float::sqrt(input.com_velocity.norm_squared()),
                MAX_RATE,
            )
            && within(input.heading, MAX_COORDINATE)
            && within(input.turning_rate, MAX_RATE))
        {
            return Err(InputError::State);
        }
        if !pos_ok(&input.stance_foot) {
            return Err(InputError::StanceFoot);
        }
        if !input.time_in_step.is_finite() {
            return Err(InputError::TimeInStep);
        }
        if !pos_ok(&input.goal) {
            return Err(InputError::Goal);
        }
        let t_step = cfg.step_duration;
        let t_in = crate::clamp(input.time_in_step, 0.0, t_step);
        *time_clamped = t_in != input.time_in_step;
        let tau = t_step - t_in;

        // 1. Predict x_0 at the end of the current step.
        let (p0, v0) = self.lip.propagate(
            &input.com_position,
            &input.com_velocity,
            &input.stance_foot,
            tau,
        );
        if !(finite2(&p0) && finite2(&v0)) {
            return Err(InputError::State);
        }
        Ok((p0, v0, tau))
    }

    /// Steps 1-5 of SPEC section 2 into `out`, the obstacles being `obstacles`:
    /// `(index in input.obstacles, polygon)` in the order the selection sees
    /// them (all of `input.obstacles`, or a caller's candidates).
    fn assemble<'o, const V: usize, const NOBS: usize>(
        &self,
        input: &CycleInput<'_, V>,
        obstacles: impl Iterator<Item = (usize, &'o ConvexPolygon<V>)>,
        out: &mut Assembly<N, NV, NC, NOBS>,
    ) -> Result<(), InputError> {
        let (p0, v0, tau) = self.end_of_step(input, &mut out.time_clamped)?;
        let cfg = &self.config;
        let t_step = cfg.step_duration;
        let theta0 = wrap_angle(input.heading + input.turning_rate * tau);
        if !theta0.is_finite() {
            return Err(InputError::State);
        }
        // 2. Headings.
        let heading = plan_heading::<N>(
            theta0,
            [p0.x, p0.y],
            [input.goal.x, input.goal.y],
            t_step,
            cfg.omega_max,
            cfg.heading_freeze_radius,
        );
        let first_side = input.stance_side.opposite();
        out.prediction = Prediction {
            p0,
            v0,
            heading,
            first_side,
            goal: input.goal,
        };

        // Active obstacles: within r_active of p_0, nearest first, at most NOBS.
        out.n_obstacles = 0;
        out.obstacles_truncated = false;
        for (idx, poly) in obstacles {
            let Ok(index) = u32::try_from(idx) else {
                out.obstacles_truncated = true;
                break;
            };
            let cp = closest_point_point_polygon(&p0, poly);
            // NaN distances (impossible for validated polygons) are skipped too.
            if cp.signed_distance.is_nan() || cp.signed_distance > cfg.r_active {
                continue;
            }
            let cand = ActiveObstacle {
                index,
                distance: cp.signed_distance,
                half_plane: HalfPlane {
                    c: cp.point,
                    eta: cp.normal,
                },
            };
            // Insertion into the sorted list (bounded by NOBS), after every kept
            // obstacle that is not farther.
            let n = out.n_obstacles.min(NOBS);
            let pos = out.obstacles[..n]
                .iter()
                .rposition(|o| o.distance <= cand.distance)
                .map_or(0, |i| i + 1);
            if pos >= NOBS {
                out.obstacles_truncated = true; // full; not nearer than the farthest
                continue;
            }
            let len = if n == NOBS {
                out.obstacles_truncated = true; // the farthest drops out
                n
            } else {
                n + 1
            };
            // Put it at `pos`; each farther one moves one slot back (from the
            // end, each slot takes its predecessor's obstacle).
            let mut slots = out.obstacles[pos.min(len)..len].iter_mut().rev();
            if let Some(mut dst) = slots.next() {
                for src in slots {
                    *dst = *src;
                    dst = src;
                }
                *dst = cand;
            }
            out.n_obstacles = len;
        }

        // 4-5. Cost and rows.
        out.qp.clear();
        let (q, c) = self.model.gradient::<NV>(&input.goal);
        out.qp.q = q;
        out.cost_constant = c;
        let bounds = GaitBounds {
            vx_min: cfg.vx_min,
            vx_max: cfg.vx_max,
            vy_min: cfg.vy_min,
            vy_max: cfg.vy_max,
            l_max: cfg.l_max,
            alpha: cfg.alpha,
        };
        // Capacity is guaranteed by the compile-time check NC >= 8N + N NOBS and by
        // `new` for the foot rows; a failed push would only drop rows, so it is
        // checked anyway and reported as a numerical failure by the caller.
        let mut ok = true;
        let mut side = first_side;
        for k in 0..N {
            let m_before = out.qp.m;
            ok &= push_gait_rows(
                &mut out.qp,
                &self.model,
                &bounds,
                k,
                heading.theta[k],
                side.sign(),
                heading.omega_bar,
                &p0,
                &v0,
            )
            .is_ok();
            for (r, kind) in RowKind::GAIT.iter().enumerate() {
                if let Some(slot) = out.rows.get_mut(m_before + r) {
                    *slot = RowId {
                        kind: *kind,
                        k: k as u8,
                    };
                }
            }
            side = side.opposite();
        }
        for ob in &out.obstacles[..out.n_obstacles.min(NOBS)] {
            for k in 0..N {
                let i = out.qp.m;
                ok &= push_ldcbf_row(
                    &mut out.qp,
                    &self.model,
                    &ob.half_plane,
                    cfg.gamma,
                    self.barrier_margin,
                    k,
                    &p0,
                    &v0,
                )
                .is_ok();
                if let Some(slot) = out.rows.get_mut(i) {
                    *slot = RowId {
                        kind: RowKind::Ldcbf(ob.index),
                        k: k as u8,
                    };
                }
            }
        }
        if cfg.foot_clearance.is_some() {
            for ob in &out.obstacles[..out.n_obstacles.min(NOBS)] {
                for k in 0..N {
                    let i = out.qp.m;
                    let df = cfg.foot_margin(&ob.half_plane.eta, heading.theta[k]);
                    ok &= push_foot_row(&mut out.qp, &self.model, &ob.half_plane, df, k, &p0, &v0)
                        .is_ok();
                    if let Some(slot) = out.rows.get_mut(i) {
                        *slot = RowId {
                            kind: RowKind::FootClearance(ob.index),
                            k: k as u8,
                        };
                    }
                }
            }
        }
        debug_assert!(ok, "row capacity exceeded despite compile-time check");
        Ok(())
    }

    fn solve_assembled<const V: usize, const NOBS: usize, B: QpBackend<NV, NC>>(
        &self,
        memory: &mut Memory<NV>,
        input: &CycleInput<'_, V>,
        work: &Assembly<N, NV, NC, NOBS>,
        backend: &mut B,
    ) -> CycleOutput<N> {
        let pred = &work.prediction;
        // Shift of the horizon since the last plan: a new step began when the
        // stance side changed.
        let shift = usize::from(memory.has_plan && memory.stance != input.stance_side);
        let mut prefer = [false; NC];
        let mut warm = false;
        if self.config.warm_start {
            for id in &memory.active[..memory.n_active.min(NV)] {
                let k = id.k as usize;
                if k < shift {
                    continue;
                }
                let target = RowId {
                    kind: id.kind,
                    k: (k - shift) as u8,
                };
                let used = work.qp.m.min(NC);
                for (p, r) in prefer.iter_mut().zip(&work.rows[..used]) {
                    if *r == target {
                        *p = true;
                        warm = true;
                        break;
                    }
                }
            }
        }
        let sol = backend.solve_qp(&self.solver, &work.qp, &prefer, self.config.max_iter);
        let min_h0 = work
            .active_obstacles()
            .iter()
            .map(|o| o.half_plane.h(&pred.p0, self.barrier_margin))
            .fold(f64::INFINITY, f64::min);
        let inside = work
            .active_obstacles()
            .first()
            .is_some_and(|o| o.distance <= 0.0);
        let mut info = CycleInfo {
            qp_status: Some(sol.status),
            iterations: sol.iterations,
            active_set_size: sol.n_active as u8,
            active_obstacles: work.n_obstacles as u8,
            obstacles_truncated: work.obstacles_truncated,
            inside_obstacle: inside,
            time_clamped: work.time_clamped,
            warm_started: warm,
            source: CommandSource::Optimal,
            cost: f64::NAN,
            max_violation: f64::NAN,
            min_h0,
            relax_gait: 0.0,
            relax_safety: 0.0,
            relax_capture: 0.0,
        };
        // `z`: this cycle's decision vector (positions); `feet`: set for the
        // fallbacks, which are defined by their footsteps.
        let (z, fallback_feet, status) = match sol.status {
            QpStatus::Solved => {
                remember_active(memory, &sol, work);
                (sol.x, None, CycleStatus::Optimal)
            }
            other => {
                let status = match other {
                    QpStatus::Infeasible => CycleStatus::Infeasible,
                    QpStatus::IterationLimit => CycleStatus::BudgetExhausted,
                    _ => CycleStatus::NumericalFailure,
                };
                memory.n_active = 0;
                let relaxed = if other == QpStatus::Infeasible {
                    relax::relax(
                        &self.solver,
                        backend,
                        &work.qp,
                        &work.rows,
                        self.config.max_iter,
                        self.config.max_iter_cycle.saturating_sub(sol.iterations),
                        self.config.relax_bisections,
                        self.config.max_gait_relaxation,
                        relax::CaptureBounds::new(
                            &self.config,
                            self.model.kappa,
                            pred.heading.omega_bar,
                        ),
                        Some(&sol.lambda),
                    )
                } else {
                    Err(relax::RelaxError {
                        kind: relax::RelaxFailure::Budget,
                        iterations: 0,
                    })
                };
                if let Ok(r) = &relaxed {
                    info.iterations = info.iterations.saturating_add(r.iterations);
                    info.relax_gait = r.eps_gait;
                    info.relax_safety = r.eps_safety;
                    info.relax_capture = r.eps_capture;
                    info.source = match r.level {
                        relax::RelaxLevel::Gait => CommandSource::RelaxedGait,
                        relax::RelaxLevel::Safety => CommandSource::RelaxedSafety,
                    };
                    (r.u, None, status)
                } else {
                    // The iterations spent before the relaxation gave up count too.
                    if let Err(e) = &relaxed {
                        info.iterations = info.iterations.saturating_add(e.iterations);
                    }
                    let (feet, z, source) = self.fallback(memory, shift, work);
                    info.source = source;
                    (z, Some(feet), status)
                }
            }
        };
        // Plans computed with this cycle's headings turn at omega_bar; the
        // fallbacks stop turning.
        let omega = match info.source {
            CommandSource::Optimal | CommandSource::RelaxedGait | CommandSource::RelaxedSafety => {
                pred.heading.omega_bar
            }
            _ => 0.0,
        };
        info.max_violation = relax::class_violation(&work.qp, &work.rows, &z).max();
        info.cost = self.solver.objective(&work.qp.q, &z) + work.cost_constant;
        let plan = match &fallback_feet {
            Some(feet) => self.rollout(pred, feet, omega),
            None => self.plan_from_variables(pred, &z, omega),
        };
        let foot = plan.feet[0];
        for (k, f) in plan.feet.iter().enumerate() {
            memory.plan[2 * k] = f.x;
            memory.plan[2 * k + 1] = f.y;
        }
        memory.has_plan = true;
        memory.stance = input.stance_side;
        memory.last_target = Some(foot);
        let out = CycleOutput {
            foot_target: foot,
            turning_rate: omega,
            plan,
            status,
            info,
        };
        if output_is_finite(&out) {
            out
        } else {
            // Unreachable for finite inputs; kept so no NaN can ever leave.
            hold(memory, input, InputError::State)
        }
    }

    /// The previous plan shifted by `shift` steps (the last foot extrapolated by the
    /// last stride), if it satisfies every row of this cycle's QP.
    /// The fallback command (see the module docs): of the previous plan (shifted)
    /// and the capture steps, the first that satisfies every row of this cycle's
    /// QP; otherwise the one that keeps leg reachability with the smaller largest
    /// safety-row violation (the previous plan on ties). So the fallback never
    /// violates an LDCBF row that the other candidate satisfies.
    fn fallback<const NOBS: usize>(
        &self,
        memory: &Memory<NV>,
        shift: usize,
        work: &Assembly<N, NV, NC, NOBS>,
    ) -> (SVector<f64, NV>, SVector<f64, NV>, CommandSource) {
        let tol = 10.0 * self.config.tol_primal;
        let pred = &work.prediction;
        let capture = self.capture_step(pred);
        let cap_z = self.model.variables_from_feet(&pred.p0, &pred.v0, &capture);
        let cap_v = relax::class_violation(&work.qp, &work.rows, &cap_z);
        let Some(prev) = self.previous_plan(memory, shift) else {
            return (capture, cap_z, CommandSource::CaptureStep);
        };
        let prev_z = self.model.variables_from_feet(&pred.p0, &pred.v0, &prev);
        let prev_v = relax::class_violation(&work.qp, &work.rows, &prev_z);
        let all = |v: &relax::ClassViolation| v.max() <= tol;
        let use_prev = if all(&prev_v) {
            true
        } else if all(&cap_v) {
            false
        } else if (prev_v.reach <= tol) != (cap_v.reach <= tol) {
            prev_v.reach <= tol
        } else {
            prev_v.safety <= cap_v.safety
        };
        if use_prev {
            (prev, prev_z, CommandSource::PreviousPlan)
        } else {
            (capture, cap_z, CommandSource::CaptureStep)
        }
    }

    /// The previous plan shifted by `shift` steps (the last foot extrapolated by
    /// the last stride); `None` without a finite previous plan.
    fn previous_plan(&self, memory: &Memory<NV>, shift: usize) -> Option<SVector<f64, NV>> {
        if !memory.has_plan {
            return None;
        }
        let old = &memory.plan;
        let mut u = SVector::<f64, NV>::zeros();
        for k in 0..N {
            let src = k + shift;
            let (x, y) = if src < N {
                (old[2 * src], old[2 * src + 1])
            } else if N >= 2 {
                let last = N - 1;
                (
                    2.0 * old[2 * last] - old[2 * last - 2],
                    2.0 * old[2 * last + 1] - old[2 * last - 1],
                )
            } else {
                (old[0], old[1])
            };
            u[2 * k] = x;
            u[2 * k + 1] = y;
        }
        u.iter().all(|v| v.is_finite()).then_some(u)
    }

    /// Capture steps: `f_k = p_k + clamp_box(R(theta_k)' v_k / beta, l_max)` for
    /// `k = 0..N-1`, each from the state the previous capture step leads to, so
    /// every foot honours leg reachability.
    fn capture_step(&self, pred: &Prediction<N>) -> SVector<f64, NV> {
        let l = self.config.l_max;
        let (mut p, mut v) = (pred.p0, pred.v0);
        let mut u = SVector::<f64, NV>::zeros();
        for k in 0..N {
            let th = pred.heading.theta[k];
            let (s, c) = (libm::sin(th), libm::cos(th));
            let xi = v / self.lip.beta;
            let lon = crate::clamp(c * xi.x + s * xi.y, -l, l);
            let lat = crate::clamp(-s * xi.x + c * xi.y, -l, l);
            let f = p + Vector2::new(c * lon - s * lat, s * lon + c * lat);
            u[2 * k] = f.x;
            u[2 * k + 1] = f.y;
            (p, v) = self.lip.propagate(&p, &v, &f, self.config.step_duration);
        }
        u
    }

    /// The plan of a QP solution `z` (positions): positions are `z` itself,
    /// velocities and feet come from the inverse map of [`crate::constraints`]
    /// (exact for the QP, no forward propagation of rounding errors).
    fn plan_from_variables(
        &self,
        pred: &Prediction<N>,
        z: &SVector<f64, NV>,
        omega: f64,
    ) -> Plan<N> {
        let (feet, vel) = self.model.feet_from_variables(&pred.p0, &pred.v0, z);
        let mut states = [LipState::default(); N];
        let mut th = pred.heading.theta[0];
        for (k, st) in states.iter_mut().enumerate() {
            th += omega * self.config.step_duration;
            *st = LipState {
                position: Vector2::new(z[2 * k], z[2 * k + 1]),
                velocity: vel[k],
                heading: th,
            };
        }
        pred.plan(states, feet)
    }

    /// The plan of a fallback given by its feet `u` (interleaved): the LIP rolled
    /// forward from `x_0`.
    fn rollout(&self, pred: &Prediction<N>, u: &SVector<f64, NV>, omega: f64) -> Plan<N> {
        let mut states = [LipState::default(); N];
        let mut feet = [Vector2::zeros(); N];
        let (mut p, mut v) = (pred.p0, pred.v0);
        let mut th = pred.heading.theta[0];
        for k in 0..N {
            let f = Vector2::new(u[2 * k], u[2 * k + 1]);
            (p, v) = self.lip.propagate(&p, &v, &f, self.config.step_duration);
            th += omega * self.config.step_duration;
            states[k] = LipState {
                position: p,
                velocity: v,
                heading: th,
            };
            feet[k] = f;
        }
        pred.plan(states, feet)
    }
}

fn remember_active<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    memory: &mut Memory<NV>,
    sol: &QpSolution<NV, NC>,
    work: &Assembly<N, NV, NC, NOBS>,
) {
    let n = sol.n_active.min(NV);
    for (dst, &row) in memory.active.iter_mut().zip(&sol.active[..n]) {
        *dst = work.rows.get(row as usize).copied().unwrap_or_default();
    }
    memory.n_active = n;
}

fn hold<const N: usize, const NV: usize, const V: usize>(
    memory: &mut Memory<NV>,
    input: &CycleInput<'_, V>,
    e: InputError,
) -> CycleOutput<N> {
    let finite2 = |v: &Vector2<f64>| v.x.is_finite() && v.y.is_finite();
    let target = match memory.last_target {
        Some(t) if finite2(&t) => t,
        _ if finite2(&input.stance_foot) => input.stance_foot,
        _ => Vector2::zeros(),
    };
    memory.n_active = 0;
    memory.has_plan = false;
    let st = LipState {
        position: target,
        velocity: Vector2::zeros(),
        heading: 0.0,
    };
    CycleOutput {
        foot_target: target,
        turning_rate: 0.0,
        plan: Plan {
            x0: st,
            states: [st; N],
            feet: [target; N],
            first_side: input.stance_side.opposite(),
        },
        status: CycleStatus::InvalidInput(e),
        info: CycleInfo {
            qp_status: None,
            iterations: 0,
            active_set_size: 0,
            active_obstacles: 0,
            obstacles_truncated: false,
            inside_obstacle: false,
            time_clamped: false,
            warm_started: false,
            source: CommandSource::Hold,
            cost: f64::NAN,
            max_violation: f64::NAN,
            min_h0: f64::INFINITY,
            relax_gait: 0.0,
            relax_safety: 0.0,
            relax_capture: 0.0,
        },
    }
}

fn output_is_finite<const N: usize>(o: &CycleOutput<N>) -> bool {
    let f2 = |v: &Vector2<f64>| v.x.is_finite() && v.y.is_finite();
    let fs = |s: &LipState| f2(&s.position) && f2(&s.velocity) && s.heading.is_finite();
    f2(&o.foot_target)
        && o.turning_rate.is_finite()
        && fs(&o.plan.x0)
        && o.plan.states.iter().all(fs)
        && o.plan.feet.iter().all(f2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Config::FIELDS` is the struct's field list, in order (read off its
    /// derived `Debug`, which names every field).
    #[test]
    fn config_fields_are_the_struct_fields() {
        extern crate std;
        use std::string::String;
        use std::vec::Vec;
        let dbg = std::format!("{:?}", Config::default());
        let body = dbg.trim_start_matches("Config {").trim_end_matches('}');
        let names: Vec<String> = body
            .split(", ")
            .filter_map(|kv| kv.split_once(": ").map(|(k, _)| String::from(k.trim())))
            .filter(|k| k.chars().all(|c| c.is_ascii_lowercase() || c == '_'))
            .collect();
        assert_eq!(names, Config::FIELDS.to_vec());
    }

    type Ctl = PaperController;
    type Poly = ConvexPolygon<16>;

    fn input<'a>(obstacles: &'a [Poly]) -> CycleInput<'a, 16> {
        CycleInput {
            com_position: Vector2::new(0.0, 0.0),
            com_velocity: Vector2::new(0.0, 0.0),
            heading: 0.0,
            turning_rate: 0.0,
            stance_foot: Vector2::new(0.0, -0.05),
            stance_side: Side::Left,
            time_in_step: 0.0,
            goal: Vector2::new(5.0, 0.0),
            obstacles,
        }
    }

    #[test]
    fn default_config_is_valid_and_bad_fields_are_named() {
        assert!(Config::default().validate().is_ok());
        let c = Config {
            vx_max: -1.0,
            ..Config::default()
        };
        assert_eq!(c.validate().unwrap_err().field, "vx_max");
        let c = Config {
            gamma: 0.0,
            ..Config::default()
        };
        assert_eq!(c.validate().unwrap_err().field, "gamma");
        let c = Config {
            com_height: f64::NAN,
            ..Config::default()
        };
        assert_eq!(c.validate().unwrap_err().field, "com_height");
        let c = Config {
            foot_clearance: Some(0.1),
            ..Config::default()
        };
        assert_eq!(Ctl::new(c).unwrap_err().field, "foot_clearance");
        assert!(Controller::<3, 6, { constraint_capacity(3, 8, true) }, 8>::new(c).is_ok());
        // Valid fields whose step map cannot be inverted for the foot.
        for t in [1e-6, 1e3] {
            let c = Config {
                step_duration: t,
                ..Config::default()
            };
            assert!(c.validate().is_ok());
            assert_eq!(Ctl::new(c).unwrap_err().field, "step_duration", "T = {t}");
        }
        let c = Config {
            step_duration: 1e-3,
            ..Config::default()
        };
        assert!(Ctl::new(c).is_ok());
    }

    #[test]
    fn unconfigured_controller_holds_until_configured_in_place() {
        let mut ctl = Ctl::UNCONFIGURED;
        assert!(!ctl.is_configured());
        let wall = [Poly::new(&[[0.6, -2.0], [1.6, -2.0], [1.6, 2.0], [0.6, 2.0]]).unwrap()];
        let inp = input(&wall);
        let not_configured = CycleStatus::InvalidInput(InputError::NotConfigured);
        let out = ctl.step(&inp);
        assert_eq!(out.status, not_configured);
        assert_eq!(out.info.source, CommandSource::Hold);
        assert_eq!(out.foot_target, inp.stance_foot);
        assert_eq!(out.turning_rate, 0.0);
        assert!(output_is_finite(&out));
        let mut bad_foot = inp;
        bad_foot.stance_foot.x = f64::NAN;
        let out = ctl.step(&bad_foot);
        assert_eq!(out.status, not_configured);
        assert_eq!(out.foot_target, Vector2::zeros());
        assert!(output_is_finite(&out));
        let mut asm = Assembly::default();
        assert_eq!(ctl.assemble(&inp, &mut asm), Err(InputError::NotConfigured));
        // A failed configure leaves it unconfigured.
        let bad = Config {
            gamma: 0.0,
            ..Config::default()
        };
        assert_eq!(ctl.configure(bad).unwrap_err().field, "gamma");
        let t = Config {
            step_duration: 1e-6,
            ..Config::default()
        };
        assert_eq!(ctl.configure(t).unwrap_err().field, "step_duration");
        assert!(!ctl.is_configured());
        assert_eq!(ctl.step(&inp).status, not_configured);
        // Configured in place it behaves as `new`, cycle after cycle (the
        // warm-start memory included).
        ctl.configure(Config::default()).unwrap();
        assert!(ctl.is_configured());
        let mut fresh = Ctl::new(Config::default()).unwrap();
        let walk = |ctl: &mut Ctl, fresh: &mut Ctl| {
            let mut i = inp;
            for k in 0..6 {
                i.time_in_step = 0.1 * f64::from(k % 4);
                i.com_velocity = Vector2::new(0.3 + 0.1 * f64::from(k), 0.05);
                let (a, b) = (ctl.step(&i), fresh.step(&i));
                assert_eq!(a, b, "cycle {k}");
                assert_ne!(a.status, not_configured);
            }
        };
        walk(&mut ctl, &mut fresh);
        // A failed reconfiguration changes nothing (configuration and memory).
        let mut twin = ctl.clone();
        assert!(ctl.configure(bad).is_err());
        assert!(ctl.is_configured());
        assert_eq!(ctl.config(), &Config::default());
        walk(&mut ctl, &mut twin);
        // A successful one clears the memory: as new again.
        let cfg = Config {
            delta: 0.1,
            ..Config::default()
        };
        ctl.configure(cfg).unwrap();
        let mut fresh = Ctl::new(cfg).unwrap();
        assert_eq!(ctl.config(), fresh.config());
        walk(&mut ctl, &mut fresh);
    }

    #[test]
    fn free_walk_is_optimal_and_feasible() {
        let mut ctl = Ctl::new(Config::default()).unwrap();
        let out = ctl.step(&input(&[]));
        assert_eq!(out.status, CycleStatus::Optimal);
        assert_eq!(out.info.source, CommandSource::Optimal);
        assert!(out.info.max_violation <= 1e-9);
        assert_eq!(out.plan.first_side, Side::Right);
        // Walking towards +x: the plan moves forward.
        assert!(out.plan.states[2].position.x > 0.0);
    }

    #[test]
    fn obstacles_are_selected_nearest_first_and_truncated() {
        let mut obs = [Poly::new(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]).unwrap(); 10];
        for (i, o) in obs.iter_mut().enumerate() {
            let x = 1.0 + 0.3 * (9 - i) as f64;
            *o = Poly::new(&[[x, 1.0], [x + 0.2, 1.0], [x + 0.1, 1.2]]).unwrap();
        }
        let ctl = Ctl::new(Config::default()).unwrap();
        let mut asm = Assembly::default();
        ctl.assemble(&input(&obs), &mut asm).unwrap();
        assert_eq!(asm.n_obstacles, 8);
        assert!(asm.obstacles_truncated);
        assert_eq!(asm.obstacles[0].index, 9);
        for w in asm.obstacles[..8].windows(2) {
            assert!(w[0].distance <= w[1].distance);
        }
        assert_eq!(asm.qp.m, 8 * 3 + 8 * 3);
        assert_eq!(asm.rows[24].kind, RowKind::Ldcbf(9));
    }

    #[test]
    fn prediction_uses_remaining_time_and_current_turn_rate() {
        let ctl = Ctl::new(Config::default()).unwrap();
        let mut inp = input(&[]);
        inp.com_velocity = Vector2::new(0.3, -0.1);
        inp.heading = 3.1;
        inp.turning_rate = 0.2;
        inp.time_in_step = 0.1;
        let mut asm = Assembly::default();
        ctl.assemble(&inp, &mut asm).unwrap();
        let lip = Lip::new(9.81, 1.0, 0.4);
        let (px, vx) = lip.propagate_axis(0.0, 0.3, 0.0, 0.3);
        let (py, vy) = lip.propagate_axis(0.0, -0.1, -0.05, 0.3);
        let pr = &asm.prediction;
        assert!((pr.p0 - Vector2::new(px, py)).amax() < 1e-15);
        assert!((pr.v0 - Vector2::new(vx, vy)).amax() < 1e-15);
        // 3.1 + 0.2 * 0.3 = 3.16 > pi: wrapped.
        assert!((pr.heading.theta[0] - (3.16 - 2.0 * core::f64::consts::PI)).abs() < 1e-12);
        assert_eq!(pr.first_side, Side::Right);
        // Out-of-range time is clamped and flagged.
        inp.time_in_step = 0.5;
        ctl.assemble(&inp, &mut asm).unwrap();
        assert!(asm.time_clamped);
        assert!((asm.prediction.v0 - Vector2::new(0.3, -0.1)).amax() < 1e-15);
    }

    #[test]
    fn warm_start_follows_the_horizon_shift() {
        let mut ctl = Ctl::new(Config::default()).unwrap();
        let first = ctl.step(&input(&[]));
        assert!(first.status.is_optimal());
        let n_active = ctl.memory.n_active;
        assert!(n_active > 0);
        // Same step: same rows are preferred.
        let again = ctl.step(&input(&[]));
        assert!(again.info.warm_started);
        // The step ended: stance switches, rows of k = 0 are dropped and k >= 1
        // move to k - 1; the plan is still the same optimum as a cold solve.
        let mut next = input(&[]);
        next.stance_side = Side::Right;
        next.stance_foot = first.foot_target;
        let warm = ctl.step(&next);
        let mut cold_ctl = Ctl::new(Config::default()).unwrap();
        let cold = cold_ctl.step(&next);
        assert!((warm.foot_target - cold.foot_target).amax() < 1e-9);
        assert_eq!(warm.status, cold.status);
    }

    /// Largest violation (physical units) of the rows of `class` by the plan
    /// of `out`, on the QP of the last step.
    fn class_violation(ctl: &Ctl, out: &CycleOutput<3>, class: relax::RowClass) -> f64 {
        let asm = ctl.last_assembly();
        relax::class_violation(&asm.qp, &asm.rows, &ctl.variables_of(&out.plan)).of(class)
    }

    /// Feasibility of the last QP with the rows of `class` relaxed by `eps` and
    /// the rows of `drop` left out.
    fn feasible_with(
        ctl: &Ctl,
        class: relax::RowClass,
        eps: f64,
        drop: Option<relax::RowClass>,
    ) -> bool {
        let asm = ctl.last_assembly();
        let mut qp = DenseQp::<6, 48>::with_q(asm.qp.q);
        for i in 0..asm.qp.m {
            let c = relax::RowClass::of(asm.rows[i].kind);
            if Some(c) == drop {
                continue;
            }
            let g = asm.qp.row(i);
            let h = asm.qp.h[i] + if c == class { eps } else { 0.0 };
            qp.push_row(&g, h).unwrap();
        }
        ctl.solver().solve(&qp, &[false; 48], 500).status == QpStatus::Solved
    }

    #[test]
    fn velocity_conflict_relaxes_gait_rows_minimally() {
        let mut ctl = Ctl::new(Config::default()).unwrap();
        let mut inp = input(&[]);
        // Sideways at 1.2 m/s towards the stance side: no reachable foot brings the
        // lateral velocity into [0.1, 0.4] at the end of the next step.
        inp.com_velocity = Vector2::new(0.0, -1.2);
        let out = ctl.step(&inp);
        assert_eq!(out.status, CycleStatus::Infeasible);
        assert_eq!(out.info.source, CommandSource::RelaxedGait);
        let eps = out.info.relax_gait;
        assert!(eps > 0.0);
        assert_eq!(out.info.relax_safety, 0.0);
        assert!(class_violation(&ctl, &out, relax::RowClass::Reach) <= 1e-9);
        assert!(class_violation(&ctl, &out, relax::RowClass::Gait) <= eps * (1.0 + 1e-9) + 1e-9);
        // Minimal: 1% less relaxation is infeasible, the reported one is feasible.
        assert!(!feasible_with(
            &ctl,
            relax::RowClass::Gait,
            0.99 * eps,
            None
        ));
        assert!(feasible_with(&ctl, relax::RowClass::Gait, eps, None));
        assert!(output_is_finite(&out));
        assert_eq!(
            out.turning_rate,
            ctl.last_assembly().prediction.heading.omega_bar
        );
    }

    #[test]
    fn wall_ahead_inside_margin_relaxes_safety_but_keeps_reach() {
        let cfg = Config {
            delta: 0.3,
            ..Config::default()
        };
        let mut ctl = Ctl::new(cfg).unwrap();
        // A wall 0.05 m ahead of x_0, robot walking into it at 0.8 m/s.
        let wall = [Poly::new(&[[0.0, -2.0], [1.0, -2.0], [1.0, 2.0], [0.0, 2.0]]).unwrap()];
        let mut inp = input(&wall);
        inp.time_in_step = 0.4;
        inp.com_position = Vector2::new(-0.05, 0.0);
        inp.stance_foot = Vector2::new(-0.05, -0.05);
        inp.com_velocity = Vector2::new(0.8, 0.0);
        let out = ctl.step(&inp);
        assert_eq!(out.status, CycleStatus::Infeasible);
        assert_eq!(out.info.source, CommandSource::RelaxedSafety);
        assert!(out.info.relax_safety > 0.0);
        assert!(class_violation(&ctl, &out, relax::RowClass::Reach) <= 1e-9);
        let eps = out.info.relax_safety;
        assert!(class_violation(&ctl, &out, relax::RowClass::Safety) <= eps * (1.0 + 1e-9) + 1e-9);
        assert!(!feasible_with(
            &ctl,
            relax::RowClass::Safety,
            0.99 * eps,
            Some(relax::RowClass::Gait)
        ));
        assert!(output_is_finite(&out));
    }

    #[test]
    fn exhausted_cycle_budget_falls_back() {
        // The nominal solve of this cycle needs a few iterations to prove
        // infeasibility; the relaxation then has (almost) nothing left.
        let cfg = Config {
            max_iter: 12,
            max_iter_cycle: 12,
            ..Config::default()
        };
        let mut ctl = Ctl::new(cfg).unwrap();
        let mut inp = input(&[]);
        inp.com_velocity = Vector2::new(0.0, -1.2);
        let out = ctl.step(&inp);
        assert_eq!(out.status, CycleStatus::Infeasible);
        assert_eq!(out.info.source, CommandSource::CaptureStep);
        assert!(out.info.iterations <= 64);
        assert!(class_violation(&ctl, &out, relax::RowClass::Reach) <= 1e-9);
    }

    #[test]
    fn fallback_prefers_the_candidate_that_keeps_safety() {
        let wall = [Poly::new(&[[0.6, -2.0], [1.6, -2.0], [1.6, 2.0], [0.6, 2.0]]).unwrap()];
        let cfg = Config {
            max_iter: 1,
            ..Config::default()
        };
        let mut ctl = Ctl::new(cfg).unwrap();
        let inp = input(&wall);
        // A remembered plan that walks into the wall: the capture steps (at rest:
        // feet under the CoM, far from the wall) must win.
        ctl.memory.has_plan = true;
        ctl.memory.stance = inp.stance_side;
        ctl.memory.plan = SVector::<f64, 6>::from([0.15, 0.0, 0.3, 0.0, 0.45, 0.0]);
        let out = ctl.step(&inp);
        assert_eq!(out.status, CycleStatus::BudgetExhausted);
        assert_eq!(out.info.source, CommandSource::CaptureStep);
        let v = relax::class_violation(
            &ctl.last_assembly().qp,
            &ctl.last_assembly().rows,
            &ctl.variables_of(&out.plan),
        );
        assert!(v.safety <= 1e-9 && v.reach <= 1e-9, "{v:?}");
        // A remembered plan that satisfies every row is used as it is.
        let asm = ctl.last_assembly().clone();
        let good = ctl.solver().solve(&asm.qp, &[false; 48], 100);
        assert!(good.status.is_solved());
        let good_feet = ctl.feet_of(&asm.prediction, &good.x);
        ctl.memory.has_plan = true;
        ctl.memory.stance = inp.stance_side;
        for (k, f) in good_feet.iter().enumerate() {
            ctl.memory.plan[2 * k] = f.x;
            ctl.memory.plan[2 * k + 1] = f.y;
        }
        let out = ctl.step(&inp);
        assert_eq!(out.info.source, CommandSource::PreviousPlan);
        assert_eq!(out.plan.feet, good_feet);
        assert!((ctl.variables_of(&out.plan) - good.x).amax() < 1e-12);
    }

    #[test]
    fn long_horizons_are_accepted_and_their_plans_are_lip_rollouts() {
        fn check<const N: usize, const NV: usize, const NC: usize>() {
            let mut ctl = Controller::<N, NV, NC, 8>::new(Config::default()).unwrap();
            let wall = [Poly::new(&[[1.5, -2.0], [2.5, -2.0], [2.5, 0.3], [1.5, 0.3]]).unwrap()];
            let mut inp = input(&wall);
            inp.com_velocity = Vector2::new(0.4, 0.1);
            let out = ctl.step(&inp);
            assert_eq!(out.status, CycleStatus::Optimal, "N = {N}");
            assert!(out.info.max_violation <= 1e-9);
            // The returned feet, rolled forward through the LIP, give the
            // returned states (the plan is the spec's, in world frame).
            let lip = *ctl.lip();
            let (mut p, mut v) = (out.plan.x0.position, out.plan.x0.velocity);
            for k in 0..N {
                (p, v) = lip.propagate(&p, &v, &out.plan.feet[k], 0.4);
                let s = out.plan.states[k];
                assert!((s.position - p).amax() <= 1e-12, "N = {N}, p_{}", k + 1);
                assert!((s.velocity - v).amax() <= 1e-12, "N = {N}, v_{}", k + 1);
                // Restart from the plan's own state so the check stays local
                // (a forward rollout over many steps amplifies rounding by
                // cosh(beta T)^k).
                (p, v) = (s.position, s.velocity);
            }
            assert_eq!(out.foot_target, out.plan.feet[0]);
        }
        check::<10, 20, { constraint_capacity(10, 8, false) }>();
        check::<20, 40, { constraint_capacity(20, 8, false) }>();
    }

    #[test]
    fn non_finite_input_holds() {
        let mut ctl = Ctl::new(Config::default()).unwrap();
        let mut inp = input(&[]);
        inp.com_velocity.x = f64::NAN;
        let out = ctl.step(&inp);
        assert_eq!(out.status, CycleStatus::InvalidInput(InputError::State));
        assert_eq!(out.foot_target, inp.stance_foot);
        assert_eq!(out.info.source, CommandSource::Hold);
        inp.com_velocity.x = 0.0;
        inp.goal.y = f64::INFINITY;
        assert_eq!(
            ctl.step(&inp).status,
            CycleStatus::InvalidInput(InputError::Goal)
        );
    }

    #[test]
    fn fuzz_regression_huge_coordinates_are_invalid_input() {
        // Found by `cargo fuzz run step`: a CoM at x = 1.2e111 m gave a plan whose
        // reachability rows failed by 1e80 (all precision lost). Such inputs are
        // now rejected as out of range.
        let mut ctl = Ctl::new(Config::default()).unwrap();
        let mut inp = input(&[]);
        inp.com_position = Vector2::new(1.210_696_639_093_781_8e111, -1.2e-59);
        inp.stance_foot = Vector2::new(1.2e111, 0.0);
        inp.time_in_step = -1.2e-59;
        let out = ctl.step(&inp);
        assert_eq!(out.status, CycleStatus::InvalidInput(InputError::State));
        assert!(output_is_finite(&out));
    }

    #[test]
    fn budget_exhaustion_falls_back_to_finite_command() {
        let cfg = Config {
            max_iter: 1,
            ..Config::default()
        };
        let mut ctl = Ctl::new(cfg).unwrap();
        let out = ctl.step(&input(&[]));
        assert_eq!(out.status, CycleStatus::BudgetExhausted);
        assert_eq!(out.info.source, CommandSource::CaptureStep);
        assert!(output_is_finite(&out));
        assert_eq!(out.turning_rate, 0.0);
    }
}
