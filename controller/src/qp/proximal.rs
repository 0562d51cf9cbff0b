//! Positive semidefinite Hessians: proximal-point iterations around the dual
//! active-set solve, as in DAQP (Arnström, Bemporad, Axehill, "A dual
//! active-set solver for embedded quadratic programming using recursive LDL'
//! updates", IEEE TAC 2022, and its proximal-point extension for
//! semidefinite and linear programs).
//!
//! When `H` has no Cholesky factor but `H + eps I` has one
//! (`eps` = [`PROX_EPS`] times the largest entry of `H`, or [`PROX_EPS`] for
//! `H = 0`), the solver factors `H + eps I` once and each solve runs
//!
//! ```text
//! x_{k+1} = argmin 1/2 x'(H + eps I)x + (q - eps x_k)'x  s.t. the rows of qp
//!         = argmin 1/2 x'Hx + q'x + eps/2 |x - x_k|^2   s.t. the rows of qp
//! ```
//!
//! from `x_0 = 0`, each a strictly convex QP solved by the same dual
//! active-set iteration: the first from the caller's marks, each later one
//! resumed from the factor of the active rows the one before ended with
//! (`qp/resolve.rs`: only the linear term changes), with the rows' spans
//! (`qp/spans.rs`) and [`Orthogonal::reorder`]. The proximal point
//! method converges to a minimiser of the QP whenever one exists
//! (Rockafellar 1976). After each solve `H x + q + G' lambda =
//! eps (x_k - x_{k+1})`: the multipliers of the solve are the QP's up to
//! that residual, so the iterations stop when it is small,
//! `eps |x_{k+1} - x_k|_inf <= PROX_TOL max(1, |q|_inf)` (two solves when
//! the first finds the active set: the first moves `x` from 0 to within
//! about `eps / lambda` of the minimiser, `lambda` the smallest curvature of
//! the objective on the active rows, the second by that much); the
//! objective reported is the QP's (`1/2 x'Hx + q'x`).
//!
//! Budget: [`QpSettings::max_iter`](super::QpSettings::max_iter) covers the
//! adds plus drops of all the proximal solves together (the first enters
//! its active set, one iteration per row, the equality rows included; the
//! drops of a resumed start count too), and at
//! most [`PROX_MAX_OUTER`] proximal solves run; when either runs out the
//! status is [`QpStatus::IterationLimit`] with the last iterate (as for a QP
//! whose objective is unbounded below on the feasible set, where the
//! iterates do not converge). An empty feasible set is found by the first
//! solve, as for a definite `H` (the certificate does not involve `H`).
//!
//! Compiled in where the equality rows are (from
//! [`HOT_START_MIN_NV`](super::HOT_START_MIN_NV) variables on for the static
//! sizes, always for `Dyn`), so the small static instances of the firmware
//! keep their code; a positive definite `H` never enters this module.

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, U1};

use super::bounds::BoundRows;
use super::dense::DenseQpOf;
use super::kept::Kept;
use super::norms::RowNormsOf;
use super::orthogonal::Orthogonal;
use super::resolve::{ResolveStop, resolve};
use super::solver::DualActiveSetOf;
use super::spans::row_spans;
use crate::active_set::{self, Iterate};
use crate::linalg::copy;
use crate::solution::{QpAllocator, QpSolutionOf, QpStatus};

/// The proximal iterations stop when the stationarity residual they leave,
/// `eps |x_{k+1} - x_k|_inf`, is at most this times `max(1, |q|_inf)`.
pub const PROX_TOL: f64 = 1e-10;

/// At most this many proximal solves per solve.
pub const PROX_MAX_OUTER: u32 = 100;

impl<NV: Dim, NC: Dim> DualActiveSetOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The proximal-point iterations (module docs) on `qp` with the
    /// right-hand side `hv`, the rows `excluded` left out and at most
    /// `max_iter` adds plus drops in all, the bound rows `bounds`
    /// (`qp/bounds.rs`; `()` for none).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn solve_proximal<Bd: BoundRows>(
        &self,
        qp: &DenseQpOf<NV, NC>,
        hv: &OVector<f64, NC>,
        excluded: OVector<bool, NC>,
        norms: &mut RowNormsOf<NC>,
        bounds: Bd,
        prefer: &[bool],
        max_iter: u32,
    ) -> QpSolutionOf<NV, NC> {
        solve_start!(self, qp, qp.q, hv, excluded, norms => nv, nc, m, _q, tol, me, blocked);
        let eps = self.prox;
        let hot = self.settings.hot_start;
        let pref = active_set::marks(nc, prefer);
        let unmarked = OVector::<bool, NC>::from_element_generic(nc, U1, false);
        // (Bound rows have no span: theirs is never read.)
        let spans = row_spans(&qp.gt, m, bounds);
        // The factor of the active rows, kept from one proximal solve to the
        // next (`qp/resolve.rs`).
        let mut J = self.Linv.transpose();
        let mut R = OMatrix::<f64, NV, NV>::zeros_generic(nv, nv);
        let mut d = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut kept: Option<Kept<NV>> = None;
        let mut xk = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut qk = qp.q.clone();
        let qmax = qp.q.as_slice().iter().fold(1.0f64, |a, v| a.max(v.abs()));
        let mut used: u32 = 0;
        let mut last: Option<(Iterate<NV>, OVector<f64, NV>)> = None;
        for round in 0..PROX_MAX_OUTER {
            for ((qi, &q0), &xi) in qk
                .as_mut_slice()
                .iter_mut()
                .zip(qp.q.as_slice())
                .zip(xk.as_slice())
            {
                *qi = q0 - eps * xi;
            }
            let mut start = blocked.clone();
            let x = match kept.as_mut() {
                None => {
                    // Unconstrained minimiser x = -L^-T L^-1 q_k.
                    let mut x = self.linvt_mul(self.linv_mul(qk.as_slice()).as_slice());
                    for v in x.as_mut_slice() {
                        *v = -*v;
                    }
                    x
                }
                Some(k) => {
                    let mut x = OVector::<f64, NV>::zeros_generic(nv, U1);
                    let left = max_iter.saturating_sub(used);
                    match resolve(&mut J, &mut R, hv, k, &qk, &mut x, left, |_| false) {
                        Ok(drops) => used = used.saturating_add(drops),
                        Err(ResolveStop::Budget) => {
                            // The last iterate, as when a solve runs out.
                            let Some((it, x)) = last.take() else {
                                return active_set::stopped(nv, nc, QpStatus::IterationLimit);
                            };
                            let status = QpStatus::IterationLimit;
                            return self.proximal_answer(qp, it, x, status, max_iter);
                        }
                        Err(ResolveStop::Numerical) => {
                            return active_set::stopped(nv, nc, QpStatus::NumericalError);
                        }
                    }
                    // The active rows and every equality row (active, or
                    // redundant) stay out of the scans.
                    let s = start.as_mut_slice();
                    for b in s.iter_mut().take(me) {
                        *b = true;
                    }
                    for &a in k.act.as_slice().iter().take(k.nact) {
                        if let Some(b) = s.get_mut(usize::from(a)) {
                            *b = true;
                        }
                    }
                    x
                }
            };
            let left = max_iter.saturating_sub(used);
            let marks = if kept.is_some() { &unmarked } else { &pref };
            let factor = (&mut J, &mut R, &mut d);
            let mut factor =
                Orthogonal::new(self, qp, hv, norms, tol, x, factor, bounds, kept.as_ref());
            factor.span = Some(&spans);
            factor.reorder = true;
            let it = active_set::iterate(&mut factor, nv, m, me, start, marks, true, left, hot);
            let guessed = factor.guessed;
            let x = factor.x;
            let Some(it) = it else {
                // The orthogonal factor never asks for a restart.
                return active_set::stopped(nv, nc, QpStatus::NumericalError);
            };
            used = used.saturating_add(it.iters);
            let dx = x
                .as_slice()
                .iter()
                .zip(xk.as_slice())
                .fold(0.0f64, |a, (&u, &v)| a.max((u - v).abs()));
            copy(xk.as_mut_slice(), x.as_slice());
            let converged = eps * dx <= PROX_TOL * qmax;
            if it.status != QpStatus::Solved || converged || round + 1 == PROX_MAX_OUTER {
                let status = match it.status {
                    QpStatus::Solved if !converged => QpStatus::IterationLimit,
                    s => s,
                };
                return self.proximal_answer(qp, it, x, status, used);
            }
            // A solve the guess ended left `J`, `R` at the start from
            // scratch (no factor of its active rows): the next one starts
            // from scratch too.
            if guessed {
                kept = None;
                last = Some((it, x));
                continue;
            }
            kept = Some(Kept {
                act: it.act.clone(),
                mult: OVector::zeros_generic(nv, U1),
                nact: it.nact,
                neq: it.neq,
            });
            last = Some((it, x));
        }
        active_set::stopped(nv, nc, QpStatus::IterationLimit)
    }

    /// The answer from the iteration `it` that ended at `x`, with `status`
    /// in place of [`QpStatus::Solved`] and `used` iterations in all; the
    /// objective is the QP's.
    fn proximal_answer(
        &self,
        qp: &DenseQpOf<NV, NC>,
        it: Iterate<NV>,
        x: OVector<f64, NV>,
        status: QpStatus,
        used: u32,
    ) -> QpSolutionOf<NV, NC> {
        let nc = qp.h.shape_generic().0;
        let objective = self.objective(&qp.q, &x);
        let mut sol = it.solution(nc, x, objective, |_| 1.0);
        if sol.status == QpStatus::Solved {
            sol.status = status;
        }
        sol.iterations = used;
        sol
    }
}
