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
//! (Hessian `2 I` for every `N`), an exact reformulation of docs/maths.md §2.4; the
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
//!   of that relaxed problem (planned away from the people when a moving
//!   obstacle is in the conflict, see `give_way`) ([`CommandSource::RelaxedGait`],
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

//!
//! ## Files
//!
//! * `config`: [`Config`] and its validation;
//! * `fields`: [`Config`]'s fields by name ([`FieldValue`]);
//! * `plan`: the plan, status, diagnostics and assembly types of a cycle;
//! * `select`: obstacle selection and [`ObstacleQuery`];
//! * `input`: the measured input ([`CycleInput`], [`RecordedInput`]), its
//!   validation ([`InputError`]) and the prediction of `x_0`;
//! * `assemble`: the QP of a cycle (headings, obstacles, cost and rows);
//! * `cycle`: the cycle itself ([`Controller::step`], [`Controller::assemble`]):
//!   the solve with its warm start, the plan and the diagnostics;
//! * `recover`: an unsolved QP's relaxation ([`crate::relax`]) and fallback;
//! * `fallback`: the fallback and hold commands;
//! * `give_way`: the policy toward people (the forward speed bound near a
//!   moving obstacle, the goal of a relaxation with a person in the conflict);
//! * this file: the [`Controller`], its sizes, configuration and memory.

mod assemble;
mod config;
mod cycle;
mod fallback;
mod fields;
mod give_way;
mod input;
mod plan;
mod recover;
mod select;
#[cfg(test)]
mod tests;

pub use config::{Config, ConfigError};
pub use fields::{FieldError, FieldValue};
pub use input::{CycleInput, InputError, MAX_RATE, NO_SPEED_CAP, RecordedInput};
pub use plan::{
    Assembly, CommandSource, CycleInfo, CycleOutput, CycleStatus, LipState, Plan, Prediction, Side,
};
pub use select::{ActiveObstacle, ObstacleQuery};

use nalgebra::{ArrayStorage, SVector, Vector2};

use crate::constraints::{Condensed, RowId};
use crate::lip::Lip;
use crate::qp::{DualActiveSet, OwnSolver, QpBackend, Reprobe};
use crate::reach::ReachLimits;

/// Row capacity needed for horizon `n`, `nobs` obstacles, with or without the
/// foot-clearance rows: `8 n + n nobs (x2 with foot clearance)`.
pub const fn constraint_capacity(n: usize, nobs: usize, foot_clearance: bool) -> usize {
    8 * n + n * nobs * if foot_clearance { 2 } else { 1 }
}

/// The paper's configuration: horizon 3, up to 8 active obstacles, no foot
/// clearance rows; the QP backend `B` is [`OwnSolver`] unless given.
pub type PaperController<B = OwnSolver> =
    Controller<3, 6, { constraint_capacity(3, 8, false) }, 8, B>;

/// The paper's horizon and obstacle capacity with room for the foot-clearance
/// rows (`NC = 72`): a robot with a body and feet ([`Config::body_radius`],
/// [`Config::foot_clearance`]). The simulator runs this one. The QP backend
/// `B` is [`OwnSolver`] unless given.
pub type RobotController<B = OwnSolver> =
    Controller<3, 6, { constraint_capacity(3, 8, true) }, 8, B>;

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
/// warm-start memory and the QP backend `B`. One [`Controller::step`] per
/// control cycle.
///
/// Build it with [`Controller::new`], or, without the controller ever being
/// on the stack (embedded targets), as [`Controller::UNCONFIGURED`] in a
/// `static` (all storage zero: `.bss`, no flash) followed by
/// [`Controller::configure`] in place. `B` is the QP solver the cycle calls:
/// [`OwnSolver`] (the dual active-set method of [`crate::qp`]) unless another
/// is given with [`Controller::with_backend`] (the reference crate's Clarabel,
/// to run a whole closed loop with either solver).
#[derive(Clone, Debug)]
pub struct Controller<
    const N: usize,
    const NV: usize,
    const NC: usize,
    const NOBS: usize,
    B: QpBackend<NV, NC> = OwnSolver,
> {
    core: Core<N, NV, NC>,
    memory: Memory<NV>,
    work: Assembly<N, NV, NC, NOBS>,
    /// The row norms and the factor the cycle's solve and its relaxation's
    /// probes share (`qp/reprobe.rs`), set in place every cycle.
    probes: Reprobe<NV, NC>,
    backend: B,
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
    /// [`Config::reach_limits`] (computed once at configure).
    limits: ReachLimits,
    lip: Lip,
    model: Condensed<N>,
    solver: DualActiveSet<NV, NC>,
}

impl<const N: usize, const NV: usize, const NC: usize> Core<N, NV, NC> {
    /// The all-zero placeholder of an unconfigured controller.
    const UNCONFIGURED: Self = Core {
        configured: false,
        config: Config::UNSET,
        barrier_margin: 0.0,
        limits: ReachLimits {
            speed_max: 0.0,
            accel: 0.0,
            grow: 0.0,
        },
        lip: Lip::ZERO,
        model: Condensed::ZERO,
        solver: DualActiveSet::PLACEHOLDER,
    };
}

impl<const NV: usize> Memory<NV> {
    /// No warm start, no plan, no last target.
    const EMPTY: Self = Memory {
        active: [RowId::DEFAULT; NV],
        n_active: 0,
        plan: SVector::from_array_storage(ArrayStorage([[0.0; NV]; 1])),
        has_plan: false,
        stance: Side::Left,
        last_target: None,
    };
}

impl<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>
    Controller<N, NV, NC, NOBS>
{
    /// A controller without a configuration, all storage zero (so a `static`
    /// initialised with it lands in `.bss` and costs no flash). Until
    /// [`Controller::configure`] succeeds, [`Controller::step`] returns
    /// [`CycleStatus::InvalidInput`]`(`[`InputError::NotConfigured`]`)` with the
    /// hold command ([`CommandSource::Hold`]: the stance foot, or the origin if
    /// that is not finite, and turning rate 0), [`Controller::assemble`]
    /// returns `Err(InputError::NotConfigured)`, and [`Controller::config`]
    /// and [`Controller::lip`] return all-zero placeholders.
    pub const UNCONFIGURED: Self = Controller {
        core: Core::UNCONFIGURED,
        memory: Memory::EMPTY,
        work: Assembly::EMPTY,
        probes: Reprobe::EMPTY,
        backend: OwnSolver,
    };

    /// Validates `config` and precomputes the model and the Hessian
    /// factorisation: [`Controller::UNCONFIGURED`] followed by
    /// [`Controller::configure`].
    ///
    /// ```
    /// use ldcbf_controller::{Config, PaperController};
    ///
    /// let controller = PaperController::new(Config::default()).unwrap();
    /// assert!(controller.is_configured());
    ///
    /// let bad = Config { step_duration: -0.4, ..Config::default() };
    /// assert_eq!(PaperController::new(bad).unwrap_err().field, "step_duration");
    /// ```
    pub fn new(config: Config) -> Result<Self, ConfigError> {
        let mut controller = Self::UNCONFIGURED;
        controller.configure(config)?;
        Ok(controller)
    }
}

impl<const N: usize, const NV: usize, const NC: usize, const NOBS: usize, B: QpBackend<NV, NC>>
    Controller<N, NV, NC, NOBS, B>
{
    /// [`Controller::new`] with another QP solver `backend` (every QP of the
    /// cycle, the priority scheme's included, is solved by it).
    pub fn with_backend(config: Config, backend: B) -> Result<Self, ConfigError> {
        let mut controller = Controller {
            core: Core::UNCONFIGURED,
            memory: Memory::EMPTY,
            work: Assembly::EMPTY,
            probes: Reprobe::EMPTY,
            backend,
        };
        controller.configure(config)?;
        Ok(controller)
    }

    /// The QP backend (e.g. to read what an instrumented backend recorded).
    pub fn backend(&self) -> &B {
        &self.backend
    }

    /// The QP backend, mutable (e.g. to reset an instrumented backend between
    /// cycles).
    pub fn backend_mut(&mut self) -> &mut B {
        &mut self.backend
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
        let settings = config.qp_settings();
        let solver = DualActiveSet::new(&model.hessian::<NV>(), settings).map_err(|_| ConfigError {
            field: "com_height",
            requirement: "gives a Hessian that is not positive definite (check gravity, com_height, step_duration)",
        })?;
        // Everything is checked: commit, field by field.
        let core = &mut self.core;
        core.config = config;
        core.barrier_margin = barrier_margin;
        core.limits = config.reach_limits();
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

    /// The QP solver (holds the constant Hessian `H` and the settings). An
    /// internal for tests, benchmarks and the simulator's QP export (the QP
    /// of a cycle is `H` with [`Controller::last_assembly`]).
    #[doc(hidden)]
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

    /// The assembly of the last [`Controller::step`]: its prediction, QP rows
    /// and active obstacles (world frame W), e.g. to show the LDCBF
    /// half-planes the cycle used.
    pub fn last_assembly(&self) -> &Assembly<N, NV, NC, NOBS> {
        &self.work
    }

    /// Forgets the warm-start and fallback memory (e.g. after a restart).
    pub fn reset(&mut self) {
        self.memory.n_active = 0;
        self.memory.has_plan = false;
        self.memory.last_target = None;
    }
}
