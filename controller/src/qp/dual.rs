//! One solve of the dual active-set method (Goldfarb & Idnani), on top of
//! the factor: `DualActiveSetOf::solve_with` takes the start (from scratch,
//! or from the factor a probe kept, `qp/store.rs`), runs the dual iteration
//! (`active_set.rs`) on the orthogonal factor (`qp/orthogonal.rs`, its steps
//! `qp/step.rs`) and forms the solution. The entry points above it are
//! `qp/solve.rs`.

use nalgebra::{DefaultAllocator, Dim, OVector, U1};

use super::bounds::BoundRows;
use super::dense::DenseQpOf;
use super::norms::RowNormsOf;
use super::orthogonal::Orthogonal;
use super::settings::proximal_capable;
use super::solver::DualActiveSetOf;
use super::store::{Begin, Store};
use crate::active_set;
use crate::solution::{QpAllocator, QpSolutionOf, QpStatus};

impl<NV: Dim, NC: Dim> DualActiveSetOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The solve proper, with the linear term `q` (`qp.q`, or the proximal
    /// iteration's; the objective is the one of `qp.q`), the right-hand side
    /// `h` (`qp.h` or another), the rows `excluded[i]` left out, the
    /// Euclidean row norms in `rows` and the H^-1 norms there or computed on
    /// demand (0 = not yet), the bound rows `bounds` (`qp/bounds.rs`; `()`
    /// for none), the factor in `carry` (from scratch, or from the active
    /// rows of the solve before, `qp/reprobe.rs`; left there for the next).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn solve_with<Bd: BoundRows, S: Store<NV>>(
        &self,
        qp: &DenseQpOf<NV, NC>,
        qv: &OVector<f64, NV>,
        hv: &OVector<f64, NC>,
        excluded: OVector<bool, NC>,
        norms: &mut RowNormsOf<NC>,
        bounds: Bd,
        prefer: &[bool],
        max_iter: u32,
        mut store: S,
    ) -> QpSolutionOf<NV, NC> {
        solve_start!(self, qp, qv, hv, excluded, norms => nv, nc, m, _q, tol, me, blocked);
        let pref = active_set::marks(nc, prefer);
        // Whether any row is marked (on hosts; on bare-metal targets the
        // iteration's own test of the marks alone, which is shorter there).
        let marked = cfg!(target_os = "none") || prefer.iter().any(|&p| p);
        // From scratch, or from the factor a carry holds (`qp/store.rs`).
        let mut own = store.own(self);
        let start = store.start(Begin {
            solver: self,
            q: qv,
            h: hv,
            blocked: &mut blocked,
            me,
            max_iter,
        });
        let (x, resumed_drops) = match start {
            Ok(start) => start,
            Err(status) => return active_set::stopped(nv, nc, status),
        };
        let (J, R, kept, guess, pending) = store.parts(&mut own);
        let mut d = OVector::<f64, NV>::zeros_generic(nv, U1);
        // Rows left out are never scanned: they start (and stay) blocked as if
        // active, but never enter the active list.
        let hot = self.settings.hot_start;
        // Without equality rows (the controller's QPs) the iteration is
        // compiled with `me = 0` as a constant: no equality phase, ratio test
        // and drops from the first active row (host: 3-5 % per `step` at
        // N = 10, 20).
        macro_rules! iterate {
            ($factor:expr) => {
                if me == 0 {
                    active_set::iterate($factor, nv, m, 0, blocked, &pref, marked, max_iter, hot)
                } else {
                    active_set::iterate($factor, nv, m, me, blocked, &pref, marked, max_iter, hot)
                }
            };
        }
        // A single solve iterates on the plain factor (nothing to resume, no
        // spans). A probe does too on hosts from 16 variables on when it
        // starts from scratch (the controller's first solve of a cycle): no
        // resume hook and no test for spans in its scan; the same bits
        // (iterating on the resumed factor instead: `step` +1.4 % instructions
        // at N = 10, +0.5 % at N = 20). Smaller sizes (no spans compiled in; a
        // second copy of the iteration cost the N = 3 step 2 %) and bare-metal
        // targets: one compiled iteration per instance.
        let plain = cfg!(not(target_os = "none")) && proximal_capable::<NV>();
        let factor = (J, R, &mut d);
        macro_rules! run {
            ($kept:expr) => {{
                let mut f = Orthogonal::new(self, qp, hv, norms, tol, x, factor, bounds, $kept);
                f.guess = guess;
                f.pending = pending;
                let it = iterate!(&mut f);
                // A factor kept for the next solve is the factor: set, if
                // no step of this solve needed it (a guess keeps none).
                if !f.guessed {
                    f.settle();
                }
                (it, f.x, f.guessed)
            }};
        }
        let (it, x, guessed) = if !S::RESUMES || (plain && kept.is_none()) {
            run!(())
        } else {
            run!(kept)
        };
        let Some(it) = it else {
            // The orthogonal factor never asks for a restart.
            store.keep(None, guessed);
            return active_set::stopped(nv, nc, QpStatus::NumericalError);
        };
        // A solve the guess ended holds no factor of its active rows.
        store.keep(Some(&it), guessed);
        let objective = self.objective(&qp.q, &x);
        let mut sol = it.solution(nc, x, objective, |_| 1.0);
        sol.iterations = sol.iterations.saturating_add(resumed_drops);
        sol
    }
}
