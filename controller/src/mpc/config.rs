//! The controller's settings: [`Config`] (the paper's Table I by default),
//! its validation ([`Config::validate`], [`ConfigError`]) and the margins
//! derived from it ([`Config::barrier_margin`], [`Config::foot_margin`]).

use crate::qp::QpSettings;
use nalgebra::Vector2;

/// Controller settings. Units: SI (m, s, rad). Build with `Default` (the paper's
/// Table I) and override fields; [`Config::validate`] names the first bad field.
///
/// ```
/// use ldcbf_controller::Config;
///
/// // A robot with a 0.25 m body and a faster barrier decay than Table I's 0.3.
/// let config = Config { body_radius: 0.25, gamma: 0.5, ..Config::default() };
/// assert!(config.validate().is_ok());
///
/// let bad = Config { gamma: 0.0, ..Config::default() };
/// assert_eq!(bad.validate().unwrap_err().field, "gamma");
/// ```
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
    /// At an obstacle's vertex closest to `p_0`, turn the half-plane's normal
    /// from `(p_0 - c)/|p_0 - c|` towards the vertex's edge normal that blocks
    /// the way to the goal least, keeping at least half of `p_0`'s clearance
    /// beyond [`Config::barrier_margin`] (docs/maths.md §2.3).
    /// `false` (the default) is the paper's closest-point normal; on a map of
    /// grid cells (LiDAR) a one-cell piece in front of a wall otherwise gives a
    /// half-plane across the way.
    pub turn_vertex_normals: bool,
    /// Use the obstacles' velocity uncertainty radii
    /// ([`CycleInput::obstacle_velocity_radii`](super::CycleInput::obstacle_velocity_radii)):
    /// the barrier holds against the set a person can reach (docs/maths.md
    /// §2.7) and the robot walks no faster than it can stop in one step near
    /// one. `false`: every radius is taken as 0 (constant-velocity
    /// prediction with no margin, the baseline). Default `true`: a caller
    /// that gives no radii sees no change.
    pub velocity_margin: bool,
    /// `v_max`: the largest speed of a person of uncertain velocity, m/s
    /// (> 0; docs/maths.md §2.7). Default 1.5 (a brisk walk).
    pub person_speed_max: f64,
    /// `a_max`: the largest acceleration of a person of uncertain velocity,
    /// m/s^2 (>= 0; docs/maths.md §2.7). Default 0.5 (a walk started or
    /// stopped within about 3 s).
    pub person_accel_max: f64,
    /// The time over which the set a person of uncertain velocity can reach
    /// grows, s (finite, > 0; docs/maths.md §2.7,
    /// [`ReachLimits::grow`](crate::ReachLimits::grow)): beyond it the set
    /// keeps its radius and travels with the estimate. Default 1000 (longer
    /// than any horizon: the set grows over the whole horizon). 0.8 s (the
    /// step being taken and the one that can stop the robot) freed the robot
    /// among people standing still, but on unseen seeds let it walk into
    /// people where the whole-horizon set did not (docs/results.md).
    pub person_reach_time: f64,
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
            turn_vertex_normals: false,
            velocity_margin: true,
            person_speed_max: 1.5,
            person_accel_max: 0.5,
            person_reach_time: 1000.0,
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
    pub(super) const UNSET: Config = Config {
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
        turn_vertex_normals: false,
        velocity_margin: false,
        person_speed_max: 0.0,
        person_accel_max: 0.0,
        person_reach_time: 0.0,
    };

    /// This configuration with the iteration budgets (`max_iter`,
    /// `max_iter_cycle`) multiplied by `ceil(n / 3)`, for a controller of horizon
    /// `n`. The defaults are sized for the paper's `N = 3`; the rows and the
    /// active sets grow linearly with the horizon (closed loops on the shipped
    /// layouts needed at most 112 iterations per cycle at `N = 10` and 326 at
    /// `N = 20`, `host-sim/tests/horizon.rs`). Saturates instead of overflowing.
    pub fn with_budgets_for_horizon(self, n: usize) -> Config {
        let scale = u32::try_from(n.div_ceil(3)).unwrap_or(u32::MAX).max(1);
        Config {
            max_iter: self.max_iter.saturating_mul(scale),
            max_iter_cycle: self.max_iter_cycle.saturating_mul(scale),
            ..self
        }
    }

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
                let beta = crate::linalg::sqrt(self.gravity / self.com_height);
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

    /// The bounds of every person of uncertain velocity, for the set they
    /// can reach (docs/maths.md §2.7): `person_speed_max`,
    /// `person_accel_max`, `person_reach_time`.
    pub fn reach_limits(&self) -> crate::ReachLimits {
        crate::ReachLimits {
            speed_max: self.person_speed_max,
            accel: self.person_accel_max,
            grow: self.person_reach_time,
        }
    }

    /// The settings of the controller's QP solver: `tol_primal` and
    /// `max_iter` from here, the rest [`QpSettings::default`].
    pub fn qp_settings(&self) -> QpSettings {
        QpSettings {
            tol_primal: self.tol_primal,
            max_iter: self.max_iter,
            ..QpSettings::default()
        }
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
        if !pos(self.person_speed_max) {
            return err("person_speed_max", "must be finite and > 0");
        }
        if !nonneg(self.person_accel_max) {
            return err("person_accel_max", "must be finite and >= 0");
        }
        if !pos(self.person_reach_time) {
            return err("person_reach_time", "must be finite and > 0");
        }
        if let Err((field, requirement)) = self.qp_settings().validate() {
            return err(field, requirement);
        }
        Ok(())
    }
}
