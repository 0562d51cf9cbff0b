//! The entry points of a solve (`solve`, `solve_bounded`, `solve_selected`,
//! `solve_prepared`) and the one solve proper they all run,
//! `DualActiveSetOf::solve_with`: the start (from scratch or from a kept
//! factor, `qp/reprobe.rs`), the dual iteration (`active_set.rs`) on the
//! orthogonal factor (`qp/orthogonal.rs`), the solution.

use nalgebra::{DefaultAllocator, Dim, OVector, U1};

use super::orthogonal::Orthogonal;
use super::proximal::proximal_capable;
use super::store::{Begin, Local, Store};
use super::{
    DenseQpOf, DualActiveSetOf, QpAllocator, QpSolutionOf, QpStatus, ReprobeOf, RowNormsOf,
    SimpleBoundsOf, bounds,
};
use crate::active_set;

impl<NV: Dim, NC: Dim> DualActiveSetOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// Solves the QP `qp` with at most [`QpSettings::max_iter`](super::QpSettings::max_iter) adds plus
    /// drops. `prefer[i]` marks
    /// row `i` as expected active (warm start); pass all `false` for a cold start
    /// (entries beyond the capacity are ignored, missing ones are `false`).
    ///
    /// ```
    /// use ldcbf_controller::nalgebra::{SMatrix, SVector};
    /// use ldcbf_controller::{DenseQp, DualActiveSet, QpSettings, QpStatus};
    ///
    /// // min 1/2 |x|^2 - x_0 - x_1  subject to  x_0 + x_1 <= 1 (capacity 4 rows)
    /// let solver = DualActiveSet::<2, 4>::new(&SMatrix::identity(), QpSettings::default())
    ///     .unwrap();
    /// let mut qp = DenseQp::<2, 4>::with_q(SVector::from([-1.0, -1.0]));
    /// qp.push_row(&SVector::from([1.0, 1.0]), 1.0).unwrap();
    /// let sol = solver.solve(&qp, &[]);
    /// assert_eq!(sol.status, QpStatus::Solved);
    /// assert!((sol.x - SVector::from([0.5, 0.5])).amax() < 1e-12);
    /// assert!((sol.lambda[0] - 0.5).abs() < 1e-12); // the row is active
    /// assert_eq!(sol.iterations, 1); // one add
    /// ```
    pub fn solve(&self, qp: &DenseQpOf<NV, NC>, prefer: &[bool]) -> QpSolutionOf<NV, NC> {
        // The H^-1 norms are left to the solve, which computes them only for
        // rows found violated.
        let mut rows = RowNormsOf::euclidean(qp);
        self.solve_all_rows(qp, &mut rows, prefer)
    }

    /// [`DualActiveSetOf::solve`] with the rows `bounds` (detected from a QP
    /// with the same rows of `G` by [`SimpleBoundsOf::detect`]) handled as
    /// simple bounds (`qp/bounds.rs`): no norm, no dot product and no
    /// product with `L^-1` for them, `J' g_p` of an added bound read off a
    /// row of `J`. The same result as `solve`, bit for bit (status,
    /// iterations, active set, `x`, multipliers or certificate, objective).
    /// `bounds` detected for another number of rows gives
    /// [`QpStatus::NumericalError`].
    pub fn solve_bounded(
        &self,
        qp: &DenseQpOf<NV, NC>,
        bounds: &SimpleBoundsOf<NC>,
        prefer: &[bool],
    ) -> QpSolutionOf<NV, NC> {
        let nc = qp.h.shape_generic().0;
        let codes = &bounds.code;
        let mut rows = RowNormsOf::euclidean_except(qp, bounds);
        if bounds.m != qp.m.min(nc.value()) || bounds.code.len() != nc.value() {
            rows.finite = false;
        }
        let excluded = OVector::<bool, NC>::from_element_generic(nc, U1, false);
        let max_iter = self.settings.max_iter;
        if self.proximal() {
            return self.solve_proximal(qp, &qp.h, excluded, &mut rows, codes, prefer, max_iter);
        }
        self.solve_with(
            qp, &qp.q, &qp.h, excluded, &mut rows, codes, prefer, max_iter, Local,
        )
    }

    /// [`DualActiveSetOf::solve`] on a selection of `qp`'s rows with other
    /// right-hand sides: `min 1/2 x'Hx + q'x` subject to `g_i'x <= h[i]` for the
    /// rows `i < qp.m` with `enabled[i]`; the other rows are left out, as if
    /// absent, and `qp.h` is not used. Multipliers (or the Farkas certificate)
    /// are indexed like `qp`'s rows, 0 for the rows left out, and so are
    /// `active` and `prefer`. Bit for bit the result of `solve` on a QP holding
    /// only the enabled rows, in the same order, without copying them: the
    /// relaxation scheme ([`crate::relax`]) solves its probes so, with no
    /// second QP in memory. Every row of `qp` must be finite, enabled or not
    /// (else [`QpStatus::NumericalError`]). At most `budget` adds plus drops
    /// (a caller's remaining budget, as the relaxation's budget of a cycle),
    /// and at most [`QpSettings::max_iter`](super::QpSettings::max_iter).
    pub fn solve_selected(
        &self,
        qp: &DenseQpOf<NV, NC>,
        h: &OVector<f64, NC>,
        enabled: &[bool],
        prefer: &[bool],
        budget: u32,
    ) -> QpSolutionOf<NV, NC> {
        // A single probe: the row norms and the start from scratch of
        // `qp/reprobe.rs`, with nothing carried before it.
        let mut state = ReprobeOf::for_solver(self, qp);
        self.solve_reprobe(qp, h, enabled, prefer, budget, &mut state)
    }

    /// [`DualActiveSetOf::solve`] with the row data prepared by
    /// [`DualActiveSetOf::prepare_rows`] from a QP with the same rows of `G` (same
    /// `m`; `q` and `h` may differ). Same result as `solve`, less work per call.
    /// A `rows` prepared for a different `m` gives [`QpStatus::NumericalError`].
    pub fn solve_prepared(
        &self,
        qp: &DenseQpOf<NV, NC>,
        rows: &RowNormsOf<NC>,
        prefer: &[bool],
    ) -> QpSolutionOf<NV, NC> {
        let mut rows = rows.clone();
        let nc = qp.h.shape_generic().0;
        if rows.m != qp.m.min(nc.value()) || rows.norm2.len() != nc.value() {
            rows.finite = false;
        }
        self.solve_all_rows(qp, &mut rows, prefer)
    }

    /// `solve` and `solve_prepared` with the row norms `rows`: every row of
    /// `qp` with its `h`, from scratch, at most [`QpSettings::max_iter`](super::QpSettings::max_iter).
    #[inline(always)]
    fn solve_all_rows(
        &self,
        qp: &DenseQpOf<NV, NC>,
        rows: &mut RowNormsOf<NC>,
        prefer: &[bool],
    ) -> QpSolutionOf<NV, NC> {
        let nc = qp.h.shape_generic().0;
        let excluded = OVector::<bool, NC>::from_element_generic(nc, U1, false);
        let max_iter = self.settings.max_iter;
        if self.proximal() {
            return self.solve_proximal(qp, &qp.h, excluded, rows, (), prefer, max_iter);
        }
        self.solve_with(
            qp,
            &qp.q,
            &qp.h,
            excluded,
            rows,
            (),
            prefer,
            max_iter,
            Local,
        )
    }

    /// The solve proper, with the linear term `q` (`qp.q`, or the proximal
    /// iteration's; the objective is the one of `qp.q`), the right-hand side
    /// `h` (`qp.h` or another), the rows `excluded[i]` left out, the
    /// Euclidean row norms in `rows` and the H^-1 norms there or computed on
    /// demand (0 = not yet), the bound rows `bounds` (`qp/bounds.rs`; `()`
    /// for none), the factor in `carry` (from scratch, or from the active
    /// rows of the solve before, `qp/reprobe.rs`; left there for the next).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn solve_with<Bd: bounds::BoundRows, S: Store<NV>>(
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
