//! The entry points of a solve, the top of the solver (`solve`,
//! `solve_bounded`, `solve_selected`, `solve_prepared`, `solve_reprobe`):
//! each sets up the row norms, the rows left out and where the factor is
//! kept, then runs the proximal outer loop (`qp/proximal.rs`) for a
//! semidefinite `H`, else one solve (`qp/dual.rs`).

use nalgebra::{DefaultAllocator, Dim, OVector, U1};

use super::bounds::SimpleBoundsOf;
use super::dense::DenseQpOf;
use super::norms::RowNormsOf;
use super::reprobe::ReprobeOf;
use super::solver::DualActiveSetOf;
use super::store::Local;
use crate::solution::{QpAllocator, QpSolutionOf};

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
    /// [`QpStatus::NumericalError`](crate::solution::QpStatus::NumericalError).
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
    /// (else [`QpStatus::NumericalError`](crate::solution::QpStatus::NumericalError)). At most `budget` adds plus drops
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
    /// A `rows` prepared for a different `m` gives [`QpStatus::NumericalError`](crate::solution::QpStatus::NumericalError).
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

    /// [`DualActiveSetOf::solve_selected`] (the rows `enabled` of `qp` with
    /// the right-hand side `h`, at most `budget` adds plus drops) as one of
    /// a series of probes of the same QP that share `state` (`qp/reprobe.rs`):
    /// the row norms are computed once, by [`ReprobeOf::new`], and each probe
    /// after the first continues from the factor of the active rows the one
    /// before ended with. The same optimum, or the same proof of emptiness
    /// (a Farkas certificate, possibly another one), as `solve_selected`; the
    /// marks `prefer` choose among violated rows as there. `state` must
    /// have been built for this `qp`'s rows `G` (and `m`) and used only with
    /// this solver's `H`.
    /// Where the proximal iterations run (a semidefinite `H`), each probe is
    /// `solve_selected` with the shared row norms.
    pub fn solve_reprobe(
        &self,
        qp: &DenseQpOf<NV, NC>,
        h: &OVector<f64, NC>,
        enabled: &[bool],
        prefer: &[bool],
        budget: u32,
        state: &mut ReprobeOf<NV, NC>,
    ) -> QpSolutionOf<NV, NC> {
        let nc = qp.h.shape_generic().0;
        let mut excluded = OVector::<bool, NC>::from_element_generic(nc, U1, true);
        for (x, &on) in excluded.as_mut_slice().iter_mut().zip(enabled) {
            *x = !on;
        }
        let max_iter = budget.min(self.settings.max_iter);
        if self.proximal() {
            return self.solve_proximal(qp, h, excluded, &mut state.norms, (), prefer, max_iter);
        }
        self.solve_with(
            qp,
            &qp.q,
            h,
            excluded,
            &mut state.norms,
            (),
            prefer,
            max_iter,
            &mut state.carry,
        )
    }
}
