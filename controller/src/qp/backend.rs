//! [`QpBackend`]: the controller's access to a QP solver, so that a whole
//! closed loop can run with ours ([`OwnSolver`]) or another (Clarabel, in the
//! reference crate) and be compared.

use nalgebra::SVector;

use super::dense::DenseQp;
use super::reprobe::Reprobe;
use super::solver::DualActiveSet;
use crate::solution::QpSolution;

/// Something that solves the controller's QPs: the type parameter `B` of
/// [`Controller`](crate::Controller), [`OwnSolver`] (the dual active-set
/// method of this module) by default; the reference crate plugs in Clarabel
/// through this trait ([`Controller::with_backend`](crate::Controller::with_backend))
/// so a whole closed loop can be run with either solver and compared.
pub trait QpBackend<const NV: usize, const NC: usize> {
    /// Whether the provided [`QpBackend::solve_selected`] and
    /// [`QpBackend::solve_reprobe`] solve on the selected rows in place with
    /// `solver` ([`DualActiveSet::solve_selected`],
    /// [`DualActiveSet::solve_reprobe`]: [`OwnSolver`]), rather than on a
    /// compact copy of them through [`QpBackend::solve_qp`] (the default, for
    /// another solver).
    const IN_PLACE: bool = false;

    /// Solves `min 1/2 u'Hu + q'u, G u <= h` where `H = solver.hessian()` and the
    /// rest is `qp`. `prefer` and the iteration limit
    /// (`solver.settings().max_iter`) are hints an external solver may ignore.
    fn solve_qp(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        prefer: &[bool; NC],
    ) -> QpSolution<NV, NC>;

    /// [`QpBackend::solve_qp`] on the rows `i` of `qp` with `enabled[i]`, with the
    /// right-hand side `h` instead of `qp.h`, multipliers (and `prefer`) indexed
    /// like `qp`'s rows, in at most `budget` iterations (a hint, as the
    /// limit of the settings); see [`DualActiveSet::solve_selected`]. The provided
    /// method copies the enabled rows into a compact QP (on the stack) for
    /// `solve_qp` and maps the result back, or solves in place
    /// ([`QpBackend::IN_PLACE`]).
    fn solve_selected(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        h: &SVector<f64, NC>,
        enabled: &[bool; NC],
        prefer: &[bool; NC],
        budget: u32,
    ) -> QpSolution<NV, NC> {
        if Self::IN_PLACE {
            return solver.solve_selected(qp, h, enabled, prefer, budget);
        }
        let mut sub = DenseQp::with_q(qp.q);
        // Compact row -> row of `qp`, and the compact rows' warm-start marks.
        let mut orig = [0u16; NC];
        let mut sub_prefer = [false; NC];
        for (i, (g, &hi)) in qp.gt.data.0.iter().zip(h.iter()).enumerate().take(qp.m) {
            if !enabled.get(i).copied().unwrap_or(false) {
                continue;
            }
            let k = sub.m;
            // Capacity cannot be exceeded: a subset of `qp`'s rows.
            if sub.push_row(&SVector::from(*g), hi).is_ok()
                && let (Some(o), Some(p)) = (orig.get_mut(k), sub_prefer.get_mut(k))
            {
                *o = i as u16;
                *p = prefer.get(i).copied().unwrap_or(false);
            }
        }
        let s = self.solve_qp(solver, &sub, &sub_prefer);
        let mut out = QpSolution {
            lambda: SVector::zeros(),
            ..s
        };
        for (&y, &o) in s.lambda.as_slice().iter().zip(&orig).take(sub.m) {
            if let Some(l) = out.lambda.get_mut(usize::from(o)) {
                *l = y;
            }
        }
        for a in out.active.as_mut_slice().iter_mut().take(s.n_active) {
            *a = orig.get(usize::from(*a)).copied().unwrap_or(*a);
        }
        out
    }

    /// [`QpBackend::solve_selected`] as one of a series of probes of the same
    /// QP's rows (same `H` and `G`) that share `state`
    /// ([`DualActiveSet::solve_reprobe`]: each continues from the active rows
    /// of the one before). The provided method resumes in place
    /// ([`QpBackend::IN_PLACE`]), or else ignores `state` and calls
    /// `solve_selected`.
    #[allow(clippy::too_many_arguments)]
    fn solve_reprobe(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        h: &SVector<f64, NC>,
        enabled: &[bool; NC],
        prefer: &[bool; NC],
        budget: u32,
        state: &mut Reprobe<NV, NC>,
    ) -> QpSolution<NV, NC> {
        if Self::IN_PLACE {
            return solver.solve_reprobe(qp, h, enabled, prefer, budget, state);
        }
        self.solve_selected(solver, qp, h, enabled, prefer, budget)
    }
}

/// The built-in backend: [`DualActiveSet::solve`], and the selected rows
/// solved in place ([`QpBackend::IN_PLACE`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct OwnSolver;

impl<const NV: usize, const NC: usize> QpBackend<NV, NC> for OwnSolver {
    const IN_PLACE: bool = true;

    fn solve_qp(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        prefer: &[bool; NC],
    ) -> QpSolution<NV, NC> {
        solver.solve(qp, prefer)
    }
}
