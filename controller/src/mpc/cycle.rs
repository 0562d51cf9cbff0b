//! One control cycle (docs/maths.md §2): the measured input ([`CycleInput`],
//! rejected with an [`InputError`] when not finite or beyond [`MAX_RATE`] or
//! [`crate::geometry::MAX_COORDINATE`]), the prediction of `x_0`, the
//! headings, the QP's cost and rows, the solve with its warm start, the
//! priority scheme of [`crate::relax`] for an infeasible QP, and the plan of
//! the solution. The fallback commands are in `fallback`, the obstacle
//! selection in `select`.

use nalgebra::{SVector, Vector2};

use super::fallback::hold;
use super::select::among;
use super::{
    Assembly, CommandSource, Controller, Core, CycleInfo, CycleOutput, CycleStatus, LipState,
    Memory, Plan, Prediction, Side,
};
use crate::constraints::{
    GaitBounds, RowId, RowKind, push_foot_row, push_gait_rows, push_ldcbf_row,
};
use crate::geometry::{ConvexPolygon, MAX_COORDINATE};
use crate::heading::{plan_heading, wrap_angle};
use crate::qp::{QpBackend, QpSolution, QpStatus, Reprobe};
use crate::relax;

/// The input of one recorded control cycle, owned: a [`CycleInput`] whose
/// obstacles are named by an index into the caller's obstacle lists. World
/// frame W. The one recorded-input type of the workspace: the simulator's
/// replays (`ldcbf_sim::studies::replay`, lists in `Recording::obstacle_sets`)
/// and the shared test fixtures (`ldcbf_nav::fixtures::walk`) use it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordedInput {
    /// CoM position, m.
    pub com_position: Vector2<f64>,
    /// CoM velocity, m/s.
    pub com_velocity: Vector2<f64>,
    /// Heading, rad (accumulated).
    pub heading: f64,
    /// Turning rate in force, rad/s.
    pub turning_rate: f64,
    /// Stance foot position, m.
    pub stance_foot: Vector2<f64>,
    /// Stance side.
    pub stance_side: Side,
    /// Time already spent in the current step, s.
    pub time_in_step: f64,
    /// Goal given to the controller (the current subgoal), m.
    pub goal: Vector2<f64>,
    /// Index of the cycle's obstacle list among the caller's lists.
    pub obstacles: usize,
    /// The cycle's speed cap, m/s ([`CycleInput::speed_cap`]).
    pub speed_cap: f64,
}

impl RecordedInput {
    /// At rest at the origin, heading 0, left stance foot under the CoM, at the
    /// start of a step, walking to `goal` among obstacle list 0.
    pub fn at_rest(goal: Vector2<f64>) -> RecordedInput {
        RecordedInput {
            com_position: Vector2::zeros(),
            com_velocity: Vector2::zeros(),
            heading: 0.0,
            turning_rate: 0.0,
            stance_foot: Vector2::zeros(),
            stance_side: Side::Left,
            time_in_step: 0.0,
            goal,
            obstacles: 0,
            speed_cap: NO_SPEED_CAP,
        }
    }

    /// The controller input of this cycle among `obstacles` (the list that
    /// [`RecordedInput::obstacles`] names).
    pub fn input<'a, const V: usize>(
        &self,
        obstacles: &'a [ConvexPolygon<V>],
    ) -> CycleInput<'a, V> {
        CycleInput {
            com_position: self.com_position,
            com_velocity: self.com_velocity,
            heading: self.heading,
            turning_rate: self.turning_rate,
            stance_foot: self.stance_foot,
            stance_side: self.stance_side,
            time_in_step: self.time_in_step,
            goal: self.goal,
            obstacles,
            obstacle_velocities: &[],
            speed_cap: self.speed_cap,
        }
    }

    /// [`RecordedInput::input`] with moving obstacles: `velocities[i]` is the
    /// velocity of `obstacles[i]` (m/s, world frame W; see
    /// [`CycleInput::obstacle_velocities`]).
    pub fn input_moving<'a, const V: usize>(
        &self,
        obstacles: &'a [ConvexPolygon<V>],
        velocities: &'a [Vector2<f64>],
    ) -> CycleInput<'a, V> {
        CycleInput {
            obstacle_velocities: velocities,
            ..self.input(obstacles)
        }
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
    /// Obstacles (validated convex polygons, world frame), where they are at
    /// the time of this input.
    pub obstacles: &'a [ConvexPolygon<V>],
    /// Velocity of each obstacle, m/s, world frame W: `obstacle_velocities[i]`
    /// translates `obstacles[i]`, rigidly and at constant velocity over the
    /// whole horizon (no rotation). Empty: every obstacle is at rest (the
    /// static controller, bit for bit). Otherwise its length must equal
    /// `obstacles.len()` (else [`InputError::ObstacleVelocityCount`]), and the
    /// velocity of every obstacle the cycle selects (within
    /// [`Config::r_active`](super::Config::r_active)) must be finite with a
    /// speed of at most [`MAX_RATE`] (else [`InputError::ObstacleVelocity`]);
    /// the velocities of obstacles the cycle does not select are not read.
    pub obstacle_velocities: &'a [Vector2<f64>],
    /// Speed cap, m/s: an upper bound on the CoM velocity along the heading
    /// at every planned step end (`lon' v_{k+1}`, the walking-velocity row
    /// [`RowKind::VelLonUpper`](crate::constraints::RowKind::VelLonUpper)),
    /// for this cycle only. A host that sees its surroundings as it goes
    /// passes the speed from which the robot can still stop inside the space
    /// it has seen free (the capture-step limit of `docs/safety.md`). The row
    /// takes `min(vx_max, max(c, vx_min))` with `c = speed_cap` when
    /// `speed_cap >= 0`, else `c = 0` (NaN too): a cap never loosens the
    /// configured bound nor crosses the lower one. [`NO_SPEED_CAP`]
    /// (infinity) is the configured bound, bit for bit.
    pub speed_cap: f64,
}

/// [`CycleInput::speed_cap`] of a cycle without a cap (m/s): the configured
/// `vx_max` holds alone.
pub const NO_SPEED_CAP: f64 = f64::INFINITY;

/// Largest accepted CoM speed (m/s), turning rate (rad/s) and obstacle speed
/// (m/s): far beyond any walking robot or person; larger values are treated
/// as corrupted measurements.
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
    /// [`CycleInput::obstacle_velocities`] is neither empty nor as long as
    /// [`CycleInput::obstacles`].
    ObstacleVelocityCount,
    /// The velocity of a selected obstacle is not finite or its speed exceeds
    /// [`MAX_RATE`].
    ObstacleVelocity,
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
            InputError::ObstacleVelocityCount => {
                "obstacle velocities are neither empty nor one per obstacle"
            }
            InputError::ObstacleVelocity => "an obstacle velocity is not finite or out of range",
            InputError::NotConfigured => "the controller is not configured",
        })
    }
}

impl core::error::Error for InputError {}

impl<const N: usize, const NV: usize, const NC: usize, const NOBS: usize, B: QpBackend<NV, NC>>
    Controller<N, NV, NC, NOBS, B>
{
    /// docs/maths.md §2.1-2.5: prediction, headings, obstacle selection
    /// (among `candidates` as in [`Controller::step`]) and all QP rows,
    /// written into `out`. Pure: uses no warm-start memory.
    /// `Err(InputError::NotConfigured)` (and `out` unchanged) on an
    /// unconfigured controller.
    pub fn assemble<const V: usize>(
        &self,
        input: &CycleInput<'_, V>,
        candidates: Option<&[u32]>,
        out: &mut Assembly<N, NV, NC, NOBS>,
    ) -> Result<(), InputError> {
        match candidates {
            None => self
                .core
                .assemble(input, input.obstacles.iter().enumerate(), out),
            Some(c) => self.core.assemble(input, among(input.obstacles, c), out),
        }
    }

    /// One control cycle (docs/maths.md §2): predict, plan headings, assemble and
    /// solve the QP, and return the command. Never panics on any input; the
    /// command is always finite (see the module docs for the fallbacks).
    ///
    /// `candidates`: `None` considers every obstacle of `input.obstacles`;
    /// `Some(candidates)` only the obstacles `input.obstacles[i]` for `i` in
    /// `candidates`, in the candidates' order (entries out of range are
    /// skipped). The output is bit for bit that of `None` when `candidates`
    /// is in increasing order and holds every obstacle within
    /// [`ObstacleQuery::radius`](super::ObstacleQuery::radius) of
    /// [`ObstacleQuery::center`](super::ObstacleQuery::center)
    /// ([`Controller::obstacle_query`]; a superset is fine): the cycle skips
    /// every other obstacle without side effect, keeps the rest in slice
    /// order (nearer first, ties in slice order), and identifies them (in
    /// [`ActiveObstacle::index`](super::ActiveObstacle::index), the row ids
    /// and so the warm start) by their index in `input.obstacles`, which is
    /// unchanged. The cost is that of the candidates only, whatever the
    /// length of `input.obstacles` (for a caller whose map sits in a spatial
    /// index). The QP is solved by the controller's backend `B`.
    ///
    /// A robot at rest at the origin, facing +x, walks to (3, 0) past a box
    /// (`controller/examples/closed_loop.rs` runs the whole loop):
    ///
    /// ```
    /// use ldcbf_controller::nalgebra::Vector2;
    /// use ldcbf_controller::{
    ///     CommandSource, Config, ConvexPolygon, CycleStatus, PaperController, RecordedInput,
    /// };
    ///
    /// let mut controller = PaperController::new(Config::default()).unwrap();
    /// let obstacles =
    ///     [ConvexPolygon::<8>::hull(&[[1.0, 0.3], [1.5, 0.3], [1.5, 0.8], [1.0, 0.8]]).unwrap()];
    /// // At rest, left foot under the CoM, at the start of a step.
    /// let input = RecordedInput::at_rest(Vector2::new(3.0, 0.0)).input(&obstacles);
    /// let out = controller.step(&input, None);
    /// assert_eq!(out.status, CycleStatus::Optimal);
    /// assert_eq!(out.info.source, CommandSource::Optimal);
    /// assert_eq!(out.info.active_obstacles, 1);
    /// // The swing foot lands within reach of the CoM at the step end (l_max in
    /// // each body axis; heading 0, so body and world axes agree) ...
    /// let reach = (out.foot_target - out.plan.x0.position).amax();
    /// assert!(reach <= Config::default().l_max + 1e-9);
    /// // ... and the planned CoM moves towards the goal.
    /// assert!(out.plan.states[2].position.x > out.plan.states[0].position.x);
    /// ```
    // Always inlined, so that a caller passing `None` (or `Some`) as a
    // constant gets the one path it uses, with no test and no second copy of
    // the cycle (the firmware's instructions and flash).
    #[inline(always)]
    pub fn step<const V: usize>(
        &mut self,
        input: &CycleInput<'_, V>,
        candidates: Option<&[u32]>,
    ) -> CycleOutput<N> {
        match candidates {
            None => self.cycle_among(input, input.obstacles.iter().enumerate()),
            Some(c) => self.cycle_among(input, among(input.obstacles, c)),
        }
    }

    /// [`Controller::step`] with the obstacles `obstacles`: `(index in
    /// input.obstacles, polygon)` in the order the selection sees them.
    fn cycle_among<'o, const V: usize>(
        &mut self,
        input: &CycleInput<'_, V>,
        obstacles: impl Iterator<Item = (usize, &'o ConvexPolygon<V>)>,
    ) -> CycleOutput<N> {
        let Controller {
            core,
            memory,
            work,
            probes,
            backend,
        } = self;
        match core.assemble(input, obstacles, work) {
            Ok(()) => core.solve_assembled(memory, input, work, probes, backend),
            Err(e) => hold(memory, input, e),
        }
    }
}

impl<const N: usize, const NV: usize, const NC: usize> Core<N, NV, NC> {
    /// Validates the measured input and predicts `(p_0, v_0, tau)`: the CoM
    /// state at the end of the current step (docs/maths.md §2.1) and the
    /// time left until then, s. Sets `time_clamped` once the time in step is
    /// known to be finite.
    pub(super) fn end_of_step<const V: usize>(
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
                crate::linalg::sqrt(input.com_velocity.norm_squared()),
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
        if !(input.obstacle_velocities.is_empty()
            || input.obstacle_velocities.len() == input.obstacles.len())
        {
            return Err(InputError::ObstacleVelocityCount);
        }
        let t_step = cfg.step_duration;
        let t_in = crate::linalg::clamp(input.time_in_step, 0.0, t_step);
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

    /// docs/maths.md §2.1-2.5 into `out`, the obstacles being `obstacles`:
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
            time_to_p0: tau,
        };

        // 3. Active obstacles: within r_active of p_0, nearest first, at most NOBS.
        out.select_obstacles(&p0, cfg, obstacles, input.obstacle_velocities)?;

        // 4-5. Cost and rows.
        out.qp.clear();
        let (q, c) = self.model.gradient::<NV>(&input.goal);
        out.qp.q = q;
        out.cost_constant = c;
        // Near a moving obstacle, no faster than the robot can stop in one
        // step, reached as fast as it can brake.
        let vx_max = self.forward_speed_bounds(
            &out.obstacles[..out.n_obstacles.min(NOBS)],
            input.obstacle_velocities,
            tau,
            &v0,
            heading.omega_bar,
        );
        // The host's speed cap tightens the longitudinal upper bound only
        // (`CycleInput::speed_cap`); no cap keeps the bounds above bit for bit.
        let cap = if input.speed_cap >= 0.0 {
            input.speed_cap
        } else {
            0.0
        };
        let mut bounds = GaitBounds {
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
        for (k, &vx) in vx_max.iter().enumerate() {
            let m_before = out.qp.m;
            bounds.vx_max = if cap < vx { cap.max(cfg.vx_min) } else { vx };
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
        // Step end k is at t_k = tau + k T from the input; a moving obstacle's
        // half-plane is taken there (`HalfPlane::h_at`).
        let step_times = |k: usize| (tau + k as f64 * t_step, tau + (k + 1) as f64 * t_step);
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
                    step_times(k),
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
                    ok &= push_foot_row(
                        &mut out.qp,
                        &self.model,
                        &ob.half_plane,
                        df,
                        k,
                        step_times(k),
                        &p0,
                        &v0,
                    )
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

    /// Solves the assembled QP `work` (warm-started from `memory`), falls
    /// back when it has no solution, and returns the command with its plan,
    /// remembering what the next cycle needs in `memory`.
    fn solve_assembled<const V: usize, const NOBS: usize, B: QpBackend<NV, NC>>(
        &self,
        memory: &mut Memory<NV>,
        input: &CycleInput<'_, V>,
        work: &mut Assembly<N, NV, NC, NOBS>,
        reprobe: &mut Reprobe<NV, NC>,
        backend: &mut B,
    ) -> CycleOutput<N> {
        // Shift of the horizon since the last plan: a new step began when the
        // stance side changed.
        let shift = usize::from(memory.has_plan && memory.stance != input.stance_side);
        let (prefer, warm) = self.warm_start(memory, shift, work);
        // The probes of an infeasible cycle's relaxation continue from this
        // solve's factor (`reprobe`).
        reprobe.restart(&self.solver, &work.qp);
        let sol = backend.solve_reprobe(
            &self.solver,
            &work.qp,
            &work.qp.h,
            &[true; NC],
            &prefer,
            self.solver.settings().max_iter,
            reprobe,
        );
        let mut info = self.info(&sol, work, warm);
        // `z`: this cycle's decision vector (positions); `feet`: set for the
        // fallbacks, which are defined by their footsteps.
        let (z, fallback_feet, status) = match sol.status {
            QpStatus::Solved => {
                remember_active(memory, sol.active_set(), work);
                (sol.x, None, CycleStatus::Optimal)
            }
            _ => {
                memory.n_active = 0;
                self.recover(
                    memory,
                    backend,
                    work,
                    (&sol, &prefer),
                    shift,
                    &mut info,
                    reprobe,
                )
            }
        };
        let pred = &work.prediction;
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

    /// The warm-start marks of this cycle's rows: the rows active in the last
    /// solved QP, moved `shift` steps earlier (a new step began), and whether
    /// any was found.
    // Inlined: one call site on the cycle path (firmware instructions).
    #[inline(always)]
    fn warm_start<const NOBS: usize>(
        &self,
        memory: &Memory<NV>,
        shift: usize,
        work: &Assembly<N, NV, NC, NOBS>,
    ) -> ([bool; NC], bool) {
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
        (prefer, warm)
    }

    /// The diagnostics of a cycle whose nominal QP returned `sol`: the
    /// solver's figures and the obstacles' (the command's source, cost,
    /// violation and relaxations are set later).
    // Inlined: one call site on the cycle path (firmware instructions).
    #[inline(always)]
    fn info<const NOBS: usize>(
        &self,
        sol: &QpSolution<NV, NC>,
        work: &Assembly<N, NV, NC, NOBS>,
        warm: bool,
    ) -> CycleInfo {
        let pred = &work.prediction;
        let min_h0 = work
            .active_obstacles()
            .iter()
            .map(|o| {
                o.half_plane
                    .h_at(&pred.p0, self.barrier_margin, pred.time_to_p0)
            })
            .fold(f64::INFINITY, f64::min);
        let inside = work
            .active_obstacles()
            .first()
            .is_some_and(|o| o.distance <= 0.0);
        CycleInfo {
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
        }
    }

    /// A cycle whose nominal QP was not solved (`sol`): the priority scheme
    /// of [`crate::relax`] when it is infeasible, else (or when that cannot
    /// finish) a fallback. Returns the decision vector, the fallback's feet
    /// (interleaved, m, world; `None` for a relaxed plan) and the status; records the source,
    /// iterations and relaxations in `info`.
    // Inlined: one call site on the cycle path (firmware instructions).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn recover<const NOBS: usize, B: QpBackend<NV, NC>>(
        &self,
        memory: &mut Memory<NV>,
        backend: &mut B,
        work: &mut Assembly<N, NV, NC, NOBS>,
        (sol, prefer): (&QpSolution<NV, NC>, &[bool; NC]),
        shift: usize,
        info: &mut CycleInfo,
        reprobe: &mut Reprobe<NV, NC>,
    ) -> (SVector<f64, NV>, Option<SVector<f64, NV>>, CycleStatus) {
        let status = match sol.status {
            QpStatus::Infeasible => CycleStatus::Infeasible,
            QpStatus::IterationLimit => CycleStatus::BudgetExhausted,
            _ => CycleStatus::NumericalFailure,
        };
        // A person in the conflict: the relaxation plans away from them
        // (`give_way`); the nominal cost is restored after it.
        let nominal_q = work.qp.q;
        let mut give_way = None;
        if sol.status == QpStatus::Infeasible
            && let Some(goal) = self.give_way_goal(work, &sol.lambda)
        {
            work.qp.q = self.model.gradient::<NV>(&goal).0;
            // Its first probe starts from scratch, adding the rows of the
            // warm start (`prefer`) first.
            give_way = Some(prefer);
        }
        let relaxed = if sol.status == QpStatus::Infeasible {
            relax::relax(
                &self.solver,
                backend,
                &work.qp,
                &work.rows,
                relax::Params {
                    max_iter: self.config.max_iter,
                    budget: self.config.max_iter_cycle.saturating_sub(sol.iterations),
                    probes: self.config.relax_bisections,
                    gait_cap: self.config.max_gait_relaxation,
                    capture: relax::CaptureBounds::new(
                        &self.config,
                        self.model.kappa,
                        work.prediction.heading.omega_bar,
                    ),
                    certificate: Some(&sol.lambda),
                    give_way,
                },
                reprobe,
            )
        } else {
            Err(relax::RelaxError {
                kind: relax::RelaxFailure::Budget,
                iterations: 0,
            })
        };
        work.qp.q = nominal_q;
        match relaxed {
            Ok(r) => {
                if give_way.is_some() {
                    // The next cycle's warm start: the rows active at this
                    // relaxed plan's solve, for its nominal solve and, when
                    // it gives way too, its first probe.
                    remember_active(memory, reprobe.active(), work);
                }
                info.iterations = info.iterations.saturating_add(r.iterations);
                info.relax_gait = r.eps_gait;
                info.relax_safety = r.eps_safety;
                info.relax_capture = r.eps_capture;
                info.source = match r.level {
                    relax::RelaxLevel::Gait => CommandSource::RelaxedGait,
                    relax::RelaxLevel::Safety => CommandSource::RelaxedSafety,
                };
                (r.u, None, status)
            }
            Err(e) => {
                // The iterations spent before the relaxation gave up count too.
                info.iterations = info.iterations.saturating_add(e.iterations);
                let (feet, z, source) = self.fallback(memory, shift, work);
                info.source = source;
                (z, Some(feet), status)
            }
        }
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
}

/// Remembers the rows `active` (indices into `work`'s rows) as the next
/// cycle's warm start.
fn remember_active<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    memory: &mut Memory<NV>,
    active: &[u16],
    work: &Assembly<N, NV, NC, NOBS>,
) {
    let n = active.len().min(NV);
    for (dst, &row) in memory.active.iter_mut().zip(active) {
        *dst = work.rows.get(row as usize).copied().unwrap_or_default();
    }
    memory.n_active = n;
}

pub(super) fn output_is_finite<const N: usize>(o: &CycleOutput<N>) -> bool {
    let f2 = |v: &Vector2<f64>| v.x.is_finite() && v.y.is_finite();
    let fs = |s: &LipState| f2(&s.position) && f2(&s.velocity) && s.heading.is_finite();
    f2(&o.foot_target)
        && o.turning_rate.is_finite()
        && fs(&o.plan.x0)
        && o.plan.states.iter().all(fs)
        && o.plan.feet.iter().all(f2)
}
