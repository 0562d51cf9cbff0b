//! Range-space (least-distance) dual active-set solve for a fixed constraint
//! matrix: the same QPs, the same rules and the same results as
//! [`DualActiveSet::solve`], organised for many solves with one `G` (only `q`
//! and `h` change, as in a linear MPC with fixed constraints).
//!
//! With `H = L L'` (the factor kept by [`DualActiveSet`]), the change of
//! variables `u = L'x + v`, `v = L^-1 q` turns
//!
//! ```text
//! minimise 1/2 x'Hx + q'x  s.t.  G x <= h
//! ```
//!
//! into the least-distance problem (LDP)
//!
//! ```text
//! minimise 1/2 |u|^2  s.t.  M u <= d,   M = G L^-T,  d = h + M v,
//! ```
//!
//! with `x = L^-T (u - v)` (`= x_unc + L^-T u`, `x_unc = -H^-1 q`) and objective `1/2 |u|^2 - 1/2 |v|^2`. Three stages:
//!
//! * [`LdpSolver::prepare`] (once per `G`): the rows `m_i = L^-1 g_i` scaled to
//!   unit norm, their Gram matrix `K = M M'` (`NC x NC`), the violation
//!   thresholds; `O(m NV^2 + m^2 NV)`.
//! * [`LdpSolver::load`] (once per `q`, `h`): `v` and the scaled slacks at the
//!   unconstrained minimiser `u = 0`, `d_i / |m_i|`; `O(m NV)`.
//! * [`LdpSolver::solve`]: the Goldfarb–Idnani iterations on the LDP, then `x`.
//!   The active set is represented by the Cholesky factor `C` of `M_A M_A'`
//!   (`nact x nact`, lower triangular) and its inverse `C^-1`: solves with
//!   `M_A M_A'` are two small matrix-vector products, an add appends one row
//!   to each (`O(nact)`), a drop restores `C` by Givens rotations and
//!   recomputes the rows of `C^-1` below the dropped one, so an add or drop
//!   costs `O(nact^2 + nact NV)` instead of the `O(NV^2)` update of `J` in
//!   [`DualActiveSet::solve`]. The slacks of all rows are updated from `K`
//!   (`O(m (nact + 1))` per step) instead of recomputed (`O(m NV)`); the primal
//!   `u = -M_A' lambda_A` is formed once at the end.
//!
//! This is the form DAQP (Arnström, Bemporad, Axehill 2022) works in; DAQP
//! keeps an `L D L'` factor of `M_A M_A'` and recomputes slacks by products
//! with `M`. The iterations are the ones of [`DualActiveSet::solve`]: the same
//! choice of row to add (most negative slack in the metric of `H^-1`, marked
//! rows first; no hot start, as with [`QpSettings::hot_start`] off), the same partial and full steps, the same tolerances with the
//! same meaning (a row is violated when `slack / |g_i| < -tol_primal`; a new
//! row is linearly dependent on the active ones when the component of `m_p`
//! outside their span is below `tol_dependence |m_p|`), the same statuses,
//! multipliers and Farkas certificate, and `iterations` counts adds plus drops.
//! Rounding differs, so results agree to rounding, not bit for bit. The
//! iteration is the same code as [`DualActiveSet::solve`]'s (`active_set.rs`),
//! over this representation of the active set.
//!
//! Accuracy: the normal equations lose accuracy with `cond(M_A)^2`. A short
//! component `z` of a new row outside the active span is projected twice, and
//! an add whose pivot `|z|` is below [`PIVOT_FALLBACK`] restarts the solve with
//! [`DualActiveSet::solve_prepared`] (orthogonal factor) on the same data.
//!
//! A solver built for a positive semidefinite `H` (proximal-point
//! iterations, `qp/proximal.rs`) is answered by the same fallback every
//! time: the least-distance form of `H + eps I` alone would solve another
//! QP.
//!
//! Memory: an [`LdpSolver`] holds `NC x NV` scaled rows and the `NC x NC` Gram
//! matrix (8 KiB for `NC = 32`, 113 KiB for `NC = 120`), so it is meant for
//! hosts or for small `NC`; the controller (whose `G` changes every cycle)
//! does not use it.
#![allow(non_snake_case)]

use nalgebra::{Const, DefaultAllocator, Dim, OMatrix, OVector, U1};

use crate::active_set;
use crate::linalg::{column, column_mut, columns, dot_d};

mod gram;
use crate::qp::{
    DenseQpOf, DualActiveSetOf, QpAllocator, QpSolutionOf, QpStatus, RowNormsOf, ZERO_ROW2,
};
#[cfg(doc)]
use crate::qp::{DualActiveSet, QpSettings};
use gram::Gram;

/// The least-distance form of one constraint matrix `G` for one Hessian, for
/// any dimension types (see [`LdpSolver`] for the static sizes): build once
/// with [`LdpSolverOf::prepare`], then [`LdpSolverOf::load`] and
/// [`LdpSolverOf::solve`] per `(q, h)`.
#[derive(Clone, Debug)]
pub struct LdpSolverOf<NV: Dim, NC: Dim>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The solver whose Hessian factor defines the change of variables.
    solver: DualActiveSetOf<NV, NC>,
    /// The rows of `G` (with `q = 0`, `h = 0`) and their norms, for the
    /// fallback to [`DualActiveSetOf::solve_prepared`] (see [`PIVOT_FALLBACK`]).
    qp: DenseQpOf<NV, NC>,
    /// Row norms of `qp` for the fallback.
    norms: RowNormsOf<NC>,
    /// Column `i`: `m_i / |m_i|` with `m_i = L^-1 g_i` (dimensionless; zero
    /// for zero rows).
    mhat: OMatrix<f64, NV, NC>,
    /// Column `i`: `L^-T mhat_i = H^-1 g_i / |m_i|` (units of `x` per unit of
    /// the scaled multiplier; zero for zero rows): `x` moves by `-lambda_i`
    /// times it when the scaled multiplier of row `i` is `lambda_i`, so the
    /// solve recovers `x` from the active rows alone.
    dx: OMatrix<f64, NV, NC>,
    /// Gram matrix of the scaled rows, `K_ij = mhat_i . mhat_j` (unit diagonal
    /// for non-zero rows); rows and columns `m..NC` are zero.
    K: OMatrix<f64, NC, NC>,
    /// `1 / |m_i|` (units of `1 / (G L^-T)`), 0 for zero rows.
    inv_mnorm: OVector<f64, NC>,
    /// Violation threshold on the squared scaled slack:
    /// `tol_primal^2 |g_i|^2 / |m_i|^2`.
    thr: OVector<f64, NC>,
    /// Row `i` is a zero row (`|g_i|^2` or `|m_i|^2` is 0): never added.
    zero: OVector<bool, NC>,
    /// Rows covered.
    m: usize,
    /// Every entry of `M` and `K` is finite.
    finite: bool,
}

/// [`LdpSolverOf`] with the sizes as constants (stack only).
pub type LdpSolver<const NV: usize, const NC: usize> = LdpSolverOf<Const<NV>, Const<NC>>;
/// [`LdpSolverOf`] with run-time sizes (feature `alloc`).
#[cfg(feature = "alloc")]
pub type LdpSolverDyn = LdpSolverOf<nalgebra::Dyn, nalgebra::Dyn>;

/// The per-`(q, h)` data of an LDP solve, from [`LdpSolverOf::load`].
#[derive(Clone, Debug)]
pub struct LdpLoadedOf<NV: Dim, NC: Dim>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// `q` and `h` as loaded, for the fallback.
    q: OVector<f64, NV>,
    /// Right-hand side `h` as loaded.
    h: OVector<f64, NC>,
    /// `v = L^-1 q`, so `x = L^-T (u - v)`.
    v: OVector<f64, NV>,
    /// `|v|^2`: the objective is `1/2 |u|^2 - 1/2 |v|^2`.
    vv: f64,
    /// The unconstrained minimiser `x_unc = -L^-T v = -H^-1 q` (the `x` of
    /// `u = 0`).
    xu: OVector<f64, NV>,
    /// Scaled slacks at `u = 0`: `d_i / |m_i| = (h_i - g_i x_unc) / |m_i|`
    /// with `x_unc = -H^-1 q` (0 for zero rows).
    s0: OVector<f64, NC>,
    /// A zero row with `h_i < -tol_primal` (the problem is infeasible).
    zero_infeasible: Option<usize>,
    /// Rows covered (must match the solver's).
    m: usize,
    /// `q` and `h` are finite.
    finite: bool,
}

/// [`LdpLoadedOf`] with the sizes as constants.
pub type LdpLoaded<const NV: usize, const NC: usize> = LdpLoadedOf<Const<NV>, Const<NC>>;
/// [`LdpLoadedOf`] with run-time sizes (feature `alloc`).
#[cfg(feature = "alloc")]
pub type LdpLoadedDyn = LdpLoadedOf<nalgebra::Dyn, nalgebra::Dyn>;

impl<NV: Dim, NC: Dim> LdpSolverOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The LDP form of the rows of `qp` (its `q` and `h` are not used) for the
    /// Hessian of `solver`. Non-finite rows, or rows whose squared norms
    /// overflow, make every later solve a [`QpStatus::NumericalError`]. The
    /// equality rows of `qp` (`qp.me > 0`) are solved by the fallback
    /// ([`DualActiveSetOf::solve_prepared`]), which holds them.
    pub fn prepare(solver: &DualActiveSetOf<NV, NC>, qp: &DenseQpOf<NV, NC>) -> Self {
        let (nv, nc) = qp.gt.shape_generic();
        let n = nv.value();
        let m = qp.m.min(nc.value());
        let tol = solver.settings().tol_primal;
        let rows = DenseQpOf {
            gt: qp.gt.clone(),
            m,
            me: qp.me.min(m),
            ..DenseQpOf::with_q_generic(OVector::zeros_generic(nv, U1), nc)
        };
        let mut p = LdpSolverOf {
            // The LDP iterations have no hot start (module docs): its
            // fallback solves cold too, so both take the same path.
            solver: solver.without_hot_start(),
            norms: solver.prepare_rows(&rows),
            qp: rows,
            mhat: OMatrix::zeros_generic(nv, nc),
            dx: OMatrix::zeros_generic(nv, nc),
            K: OMatrix::zeros_generic(nc, nc),
            inv_mnorm: OVector::zeros_generic(nc, U1),
            thr: OVector::zeros_generic(nc, U1),
            zero: OVector::from_element_generic(nc, U1, false),
            m,
            finite: solver.nv().value() == n,
        };
        for (i, g) in columns(qp.gt.as_slice(), n).enumerate().take(m) {
            let n2 = dot_d::<NV>(g, g);
            let mi = solver.linv_mul(g);
            let mn2 = dot_d::<NV>(mi.as_slice(), mi.as_slice());
            if !(n2.is_finite() && mn2.is_finite()) {
                p.finite = false;
                continue;
            }
            if n2 <= ZERO_ROW2 || mn2 <= 0.0 {
                p.zero[i] = true;
                continue;
            }
            let inv = 1.0 / libm::sqrt(mn2);
            if let Some(col) = column_mut(p.mhat.as_mut_slice(), n, i) {
                for (a, b) in col.iter_mut().zip(mi.as_slice().iter()) {
                    *a = b * inv;
                }
                let d = solver.linvt_mul(col);
                if let Some(dcol) = column_mut(p.dx.as_mut_slice(), n, i) {
                    crate::linalg::copy(dcol, d.as_slice());
                }
            }
            p.inv_mnorm[i] = inv;
            p.thr[i] = tol * tol * n2 * inv * inv;
        }
        for i in 0..m {
            for j in 0..=i {
                let (Some(mi), Some(mj)) = (
                    column(p.mhat.as_slice(), n, i),
                    column(p.mhat.as_slice(), n, j),
                ) else {
                    continue;
                };
                let k = dot_d::<NV>(mi, mj);
                if let Some(e) = p.K.get_mut((i, j)) {
                    *e = k;
                }
                if let Some(e) = p.K.get_mut((j, i)) {
                    *e = k;
                }
            }
        }
        p
    }

    /// The solver this LDP was prepared for.
    pub fn solver(&self) -> &DualActiveSetOf<NV, NC> {
        &self.solver
    }

    /// Rows covered (`m` of the prepared QP).
    pub fn rows(&self) -> usize {
        self.m
    }

    /// The per-`(q, h)` data: `v = L^-1 q` and the scaled slacks at the
    /// unconstrained minimiser. `h` entries beyond the prepared `m` are
    /// ignored. Non-finite `q` or `h` make the solve a
    /// [`QpStatus::NumericalError`].
    pub fn load(&self, q: &OVector<f64, NV>, h: &OVector<f64, NC>) -> LdpLoadedOf<NV, NC> {
        let tol = self.solver.settings().tol_primal;
        let n = self.solver.nv().value();
        let v = self.solver.linv_mul(q.as_slice());
        let mut xu = self.solver.linvt_mul(v.as_slice());
        for a in xu.as_mut_slice() {
            *a = -*a;
        }
        let nc = self.inv_mnorm.shape_generic().0;
        let mut ld = LdpLoadedOf {
            q: q.clone(),
            h: h.clone(),
            vv: dot_d::<NV>(v.as_slice(), v.as_slice()),
            xu,
            v,
            s0: OVector::zeros_generic(nc, U1),
            zero_infeasible: None,
            m: self.m,
            finite: q.as_slice().iter().all(|a| a.is_finite()) && h.len() == nc.value(),
        };
        let mhat = columns(self.mhat.as_slice(), n);
        for (i, ((((&hi, &zero), &inv), mh), s0)) in h
            .as_slice()
            .iter()
            .zip(self.zero.as_slice().iter())
            .zip(self.inv_mnorm.as_slice().iter())
            .zip(mhat)
            .zip(ld.s0.as_mut_slice().iter_mut())
            .enumerate()
            .take(self.m)
        {
            if !hi.is_finite() {
                ld.finite = false;
            }
            if zero {
                let equality = i < self.qp.me;
                if active_set::zero_row_contradicts(hi, tol, equality)
                    && ld.zero_infeasible.is_none()
                {
                    ld.zero_infeasible = Some(i);
                }
                continue;
            }
            // d_i / |m_i| = h_i / |m_i| + mhat_i . v
            *s0 = hi * inv + dot_d::<NV>(mh, ld.v.as_slice());
        }
        ld
    }

    /// [`LdpSolverOf::load`] and [`LdpSolverOf::solve`] with `qp.q` and `qp.h`
    /// (`qp`'s rows must be the prepared ones; they are not read).
    pub fn solve_qp(&self, qp: &DenseQpOf<NV, NC>, prefer: &[bool]) -> QpSolutionOf<NV, NC> {
        let ld = self.load(&qp.q, &qp.h);
        self.solve(&ld, prefer)
    }

    /// Solves the loaded QP with at most [`QpSettings::max_iter`] (of the
    /// solver it was prepared with) adds plus drops; `prefer[i]`
    /// marks row `i` as expected active (warm start). Same contract as
    /// [`DualActiveSetOf::solve`]. A `loaded` from a solver with another row count
    /// gives [`QpStatus::NumericalError`].
    pub fn solve(&self, loaded: &LdpLoadedOf<NV, NC>, prefer: &[bool]) -> QpSolutionOf<NV, NC> {
        let max_iter = self.solver.settings().max_iter;
        let nv = self.solver.nv();
        let nc = self.inv_mnorm.shape_generic().0;
        if !self.finite || !loaded.finite || loaded.m != self.m {
            return active_set::stopped(nv, nc, QpStatus::NumericalError);
        }
        if let Some(i) = loaded.zero_infeasible {
            let hi = loaded.h.as_slice().get(i).copied().unwrap_or(0.0);
            return active_set::zero_row_infeasible(nv, nc, i, hi);
        }
        let me = self.qp.me;
        if self.solver.proximal() {
            // A semidefinite Hessian: the proximal iterations of the
            // orthogonal path (`qp/proximal.rs`).
            return self.fallback(loaded, prefer);
        }
        if me > 0 && !self.solver.equalities_capable() {
            // Not compiled in at this size: the fallback's answer (a
            // numerical error, as `solve`'s).
            return self.fallback(loaded, prefer);
        }
        if me == 0
            && let Some(sol) = self.unconstrained(loaded)
        {
            return sol;
        }
        let tol_dep = self.solver.settings().tol_dependence;
        // Row `i` of the factors is column `i`. For run-time sizes they start
        // with a few rows and grow as rows are added (`gram::grow`): zeroing
        // two `n x n` matrices cost more than the rest of a solve with few
        // active rows (n = 50).
        let k0 = if NV::try_to_usize().is_some() {
            nv
        } else {
            NV::from_usize(nv.value().min(gram::FIRST_ROWS))
        };
        let mut C = OMatrix::<f64, NV, NV>::zeros_generic(nv, k0);
        let mut Ci = OMatrix::<f64, NV, NV>::zeros_generic(nv, k0);
        let pref = active_set::marks(nc, prefer);
        let n = nv.value();
        let mut factor = Gram {
            ldp: self,
            n,
            s: loaded.s0.clone(),
            C: &mut C,
            Ci: &mut Ci,
            tol_dep2: tol_dep * tol_dep,
            w: OVector::zeros_generic(nv, U1),
            b: OVector::zeros_generic(nv, U1),
            z: OVector::zeros_generic(nv, U1),
            w2: OVector::zeros_generic(nv, U1),
            r2: OVector::zeros_generic(nv, U1),
            s0: &loaded.s0,
            z2: 0.0,
            dependent: false,
        };
        // Zero rows are never added: they start (and stay) blocked.
        // No hot start (module docs): `hot` is false.
        let Some(it) = active_set::iterate(
            &mut factor,
            nv,
            self.m,
            me,
            self.zero.clone(),
            &pref,
            prefer.iter().any(|&p| p),
            max_iter,
            false,
        ) else {
            // The normal equations would lose too much accuracy.
            return self.fallback(loaded, prefer);
        };
        // u = -M_A' lambda_A - u_new m_p (scaled rows, scaled multipliers),
        // and x = x_unc + L^-T u from the same weights on the columns of
        // `dx` (`L^-T mhat_i`).
        let mut u = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut x = loaded.xu.clone();
        let (mhat, dx) = (self.mhat.as_slice(), self.dx.as_slice());
        let mut add = |a: usize, la: f64| {
            if let (Some(ma), Some(da)) = (column(mhat, n, a), column(dx, n, a)) {
                for (uk, mk) in u.as_mut_slice().iter_mut().zip(ma) {
                    *uk -= la * mk;
                }
                for (xk, dk) in x.as_mut_slice().iter_mut().zip(da) {
                    *xk -= la * dk;
                }
            }
        };
        for (&a, &la) in it
            .act
            .as_slice()
            .iter()
            .zip(it.mult.as_slice().iter())
            .take(it.nact)
        {
            add(usize::from(a), la);
        }
        if let Some((p, un)) = it.adding {
            add(p, un);
        }
        self.finish(it, x, &u, loaded)
    }

    /// The answer from the iteration's end `it`, its `x` and the LDP's
    /// primal `u`: the objective `1/2 |u|^2 - 1/2 |v|^2`, the multipliers in
    /// the units of `G` (`lambda_i = lambda_hat_i / |m_i|`).
    #[inline(always)]
    fn finish(
        &self,
        it: active_set::Iterate<NV>,
        x: OVector<f64, NV>,
        u: &OVector<f64, NV>,
        loaded: &LdpLoadedOf<NV, NC>,
    ) -> QpSolutionOf<NV, NC> {
        let objective = 0.5 * (dot_d::<NV>(u.as_slice(), u.as_slice()) - loaded.vv);
        let nc = self.inv_mnorm.shape_generic().0;
        it.solution(nc, x, objective, |i| {
            self.inv_mnorm.get(i).copied().unwrap_or(1.0)
        })
    }

    /// The cheap case, after one pass over the slacks at `u = 0` and before
    /// any factor is set up: when no row is violated there (the test of the
    /// iteration's scan), the unconstrained minimiser `x = -L^-T v` is the
    /// solution, with no active row, as DAQP returns it from its setup.
    /// What the iteration would return. `None` otherwise (or on
    /// a non-finite slack, which the iteration reports).
    #[inline]
    fn unconstrained(&self, loaded: &LdpLoadedOf<NV, NC>) -> Option<QpSolutionOf<NV, NC>> {
        let m = self.m.min(loaded.s0.len());
        let holds = loaded.s0.as_slice()[..m]
            .iter()
            .zip(self.thr.as_slice())
            .zip(self.zero.as_slice())
            .all(|((&si, &thr), &zero)| zero || slack_holds(si, thr));
        if !holds {
            return None;
        }
        // u = 0, no active row: what the iteration's end gives.
        let nv = self.solver.nv();
        Some(self.finish(
            active_set::Iterate::unconstrained(nv),
            loaded.xu.clone(),
            &OVector::zeros_generic(nv, U1),
            loaded,
        ))
    }

    /// [`DualActiveSetOf::solve_prepared`] on the loaded QP: the answer for an
    /// active set too ill-conditioned for the normal equations of the LDP,
    /// and for QPs with equality rows.
    #[cold]
    fn fallback(&self, loaded: &LdpLoadedOf<NV, NC>, prefer: &[bool]) -> QpSolutionOf<NV, NC> {
        let mut qp = self.qp.clone();
        qp.q = loaded.q.clone();
        qp.h = loaded.h.clone();
        self.solver.solve_prepared(&qp, &self.norms, prefer)
    }
}

/// A scaled slack `s_i` holds to the tolerance (its square threshold
/// `thr_i`): the violation test of the scan.
#[inline(always)]
fn slack_holds(si: f64, thr: f64) -> bool {
    si >= 0.0 || si * si <= thr
}

/// A row whose component outside the span of the active rows is shorter than
/// this (relative; the rows have unit norm), i.e. a row at an angle below
/// about 1e-6 rad from that span yet not linearly dependent to
/// `tol_dependence`, makes `M_A M_A'` too ill-conditioned (condition number
/// above 1e12, so the normal equations lose all but a few digits): the solve
/// restarts with [`DualActiveSetOf::solve_prepared`] on the same data, which
/// works with an orthogonal factor. Rare: not on the LIPMWALK set or the
/// controller's exported QPs (see `docs/solvers.md`).
pub const PIVOT_FALLBACK: f64 = 1e-6;

#[cfg(test)]
mod tests;
