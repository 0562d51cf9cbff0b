//! An infeasible or unsolved cycle (docs/maths.md §2.6): the priority
//! scheme of [`crate::relax`] (gait rows first, then safety rows, planned
//! away from a person in the conflict), and when it cannot finish, the
//! fallback command of `fallback`.

use nalgebra::SVector;

use super::cycle::remember_active;
use super::{Assembly, CommandSource, Core, CycleInfo, CycleStatus, Memory};
use crate::qp::{QpBackend, QpSolution, QpStatus, Reprobe};
use crate::relax;

impl<const N: usize, const NV: usize, const NC: usize> Core<N, NV, NC> {
    /// A cycle whose nominal QP was not solved (`sol`): the priority scheme
    /// of [`crate::relax`] when it is infeasible, else (or when that cannot
    /// finish) a fallback. Returns the decision vector, the fallback's feet
    /// (interleaved, m, world; `None` for a relaxed plan) and the status; records the source,
    /// iterations and relaxations in `info`.
    // Inlined: one call site on the cycle path (firmware instructions).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn recover<const NOBS: usize, B: QpBackend<NV, NC>>(
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
        let mut moving = [false; NC];
        if sol.status == QpStatus::Infeasible
            && let Some(goal) = self.give_way_goal(work, &sol.lambda)
        {
            work.qp.q = self.model.gradient::<NV>(&goal).0;
            // Its first probe starts from scratch, adding the rows of the
            // warm start (`prefer`) first.
            give_way = Some(prefer);
            // The people's rows give way before the walls'.
            moving = Self::moving_rows(work);
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
                    moving: give_way.map(|_| &moving),
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
}
