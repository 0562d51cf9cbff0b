//! What a cycle returns and what its QP is built from: the plan ([`Plan`],
//! [`LipState`], [`Side`]), the status and diagnostics ([`CycleStatus`],
//! [`CommandSource`], [`CycleInfo`], [`CycleOutput`]), and the assembled
//! problem ([`Prediction`], [`Assembly`]).

use nalgebra::Vector2;

use super::{ActiveObstacle, InputError};
use crate::constraints::RowId;
use crate::heading::HeadingPlan;
use crate::qp::{DenseQp, QpStatus};

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
    /// [`Config::barrier_margin`](super::Config::barrier_margin); a moving
    /// obstacle's half-plane taken at `p_0`'s time), `+inf` if none.
    pub min_h0: f64,
    /// Uniform relaxation of the gait rows in the returned plan, m/s of the
    /// bounded body-frame velocity component (0 if none).
    pub relax_gait: f64,
    /// Uniform relaxation of the safety rows in the returned plan, m of `h`
    /// (0 if none).
    pub relax_safety: f64,
    /// Uniform relaxation of the capturability bound in the returned plan, m/s
    /// (0 if none or off; see
    /// [`Config::capture_fraction`](super::Config::capture_fraction)).
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
    /// Time from the input to `p_0` (the rest of the current step), s: step
    /// end `k` is at `time_to_p0 + k T` from the input, where a moving
    /// obstacle's half-plane is taken ([`crate::HalfPlane::h_at`]).
    pub time_to_p0: f64,
}

impl<const N: usize> Prediction<N> {
    /// The plan from this prediction's `x_0` (start of step 0) through the
    /// predicted end-of-step `states`, with the footsteps `feet` (m, world).
    pub(super) fn plan(&self, states: [LipState; N], feet: [Vector2<f64>; N]) -> Plan<N> {
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

/// One cycle's QP and its bookkeeping, as assembled by
/// [`Controller::assemble`](super::Controller::assemble). Public so that the
/// reference crate can solve exactly the same problem.
#[derive(Clone, Debug)]
pub struct Assembly<const N: usize, const NV: usize, const NC: usize, const NOBS: usize> {
    /// The QP: `min 1/2 z'Hz + q'z, G z <= h` (H from
    /// [`Controller::solver`](super::Controller::solver)) in the variables
    /// `z = (p_1, .., p_N)` of [`crate::constraints`];
    /// [`Controller::feet_of`](super::Controller::feet_of) gives the
    /// footsteps of a solution.
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
            time_to_p0: 0.0,
        },
        obstacles: [ActiveObstacle::ZERO; NOBS],
        n_obstacles: 0,
        obstacles_truncated: false,
        time_clamped: false,
    };

    /// Resets every field in place to [`Assembly::EMPTY`] (no temporary copy
    /// of the whole assembly).
    pub(super) fn clear_in_place(&mut self) {
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
        pred.time_to_p0 = 0.0;
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

/// Empties `qp` in place: no rows, `q`, `G` and `h` zero.
fn clear_qp_in_place<const NV: usize, const NC: usize>(qp: &mut DenseQp<NV, NC>) {
    qp.clear();
    qp.gt.fill(0.0);
    qp.h.fill(0.0);
}
