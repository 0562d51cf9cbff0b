//! One control cycle (docs/maths.md §2): [`Controller::step`] and
//! [`Controller::assemble`] run the stages of the cycle on the input of
//! `input` (validated, `x_0` predicted) and the QP of `assemble`; this file
//! solves that QP with its warm start, hands an unsolved QP to `recover`
//! (relaxation, then fallback), and assembles the output: the command, the
//! plan of the solution and the diagnostics ([`CycleInfo`]). The fallback
//! commands are in `fallback`, the obstacle selection in `select`.

use nalgebra::{SVector, Vector2};

use super::fallback::hold;
use super::select::among;
use super::{
    Assembly, CommandSource, Controller, Core, CycleInfo, CycleInput, CycleOutput, CycleStatus,
    InputError, LipState, Memory, Plan, Prediction,
};
use crate::constraints::RowId;
use crate::geometry::ConvexPolygon;
use crate::qp::{QpBackend, QpSolution, QpStatus, Reprobe};
use crate::relax;

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
        let lim = &self.limits;
        let min_h0 = work
            .active_obstacles()
            .iter()
            .map(|o| {
                o.half_plane
                    .h_at(lim, &pred.p0, self.barrier_margin, pred.time_to_p0)
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
pub(super) fn remember_active<
    const N: usize,
    const NV: usize,
    const NC: usize,
    const NOBS: usize,
>(
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
