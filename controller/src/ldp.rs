//! Range-space (least-distance) dual active-set solve for a fixed constraint
//! matrix: the same QPs, the same rules and the same results as
//! [`DualActiveSetOf::solve`], organised for many solves with one `G` (only `q`
//! and `h` change, as in a linear MPC with fixed constraints).
//!
//! With `H = L L'` (the factor kept by [`DualActiveSetOf`]), the change of
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
//! with `x = L^-T (u - v)` and objective `1/2 |u|^2 - 1/2 |v|^2`. Three stages:
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
//!   [`DualActiveSetOf::solve`]. The slacks of all rows are updated from `K`
//!   (`O(m (nact + 1))` per step) instead of recomputed (`O(m NV)`); the primal
//!   `u = -M_A' lambda_A` is formed once at the end.
//!
//! This is the form DAQP (Arnström, Bemporad, Axehill 2022) works in; DAQP
//! keeps an `L D L'` factor of `M_A M_A'` and recomputes slacks by products
//! with `M`. The iterations are the ones of [`DualActiveSetOf::solve`]: the same
//! choice of row to add (most negative slack in the metric of `H^-1`, marked
//! rows first), the same partial and full steps, the same tolerances with the
//! same meaning (a row is violated when `slack / |g_i| < -tol_primal`; a new
//! row is linearly dependent on the active ones when the component of `m_p`
//! outside their span is below `tol_dependence |m_p|`), the same statuses,
//! multipliers and Farkas certificate, and `iterations` counts adds plus drops.
//! Rounding differs, so results agree to rounding, not bit for bit.
//!
//! Accuracy: the normal equations lose accuracy with `cond(M_A)^2`. A short
//! component `z` of a new row outside the active span is projected twice, and
//! an add whose pivot `|z|` is below [`PIVOT_FALLBACK`] restarts the solve with
//! [`DualActiveSetOf::solve_prepared`] (orthogonal factor) on the same data.
//!
//! Like [`crate::qp`], written once over nalgebra's dimension types:
//! [`LdpSolver`] and [`LdpLoaded`] are the static sizes (`Const`, no heap),
//! `LdpSolverDyn` and `LdpLoadedDyn` the run-time sizes (feature `alloc`).
//!
//! Memory: an [`LdpSolver`] holds `NC x NV` scaled rows and the `NC x NC` Gram
//! matrix (8 KiB for `NC = 32`, 113 KiB for `NC = 120`), so it is meant for
//! hosts or for small `NC`; the controller (whose `G` changes every cycle)
//! does not use it.
#![allow(non_snake_case)]

use nalgebra::{Const, DefaultAllocator, Dim, OMatrix, OVector, U1};

use crate::qp::{
    DenseQpOf, DualActiveSetOf, QpAllocator, QpSolutionOf, QpStatus, RowNormsOf, ZERO_ROW2, column,
    column_mut, columns, columns_mut, copy_into, dot, givens, shift_down,
};

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
    /// Gram matrix of the scaled rows, `K_ij = mhat_i . mhat_j` (unit diagonal
    /// for non-zero rows; symmetric, so column `i` is row `i`); rows `m..NC`
    /// are zero.
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

/// [`LdpSolverOf`] with the sizes as constants (no heap).
pub type LdpSolver<const NV: usize, const NC: usize> = LdpSolverOf<Const<NV>, Const<NC>>;

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

/// [`LdpLoadedOf`] with the sizes as constants (no heap).
pub type LdpLoaded<const NV: usize, const NC: usize> = LdpLoadedOf<Const<NV>, Const<NC>>;

#[cfg(feature = "alloc")]
mod dynamic {
    use nalgebra::Dyn;

    use super::{LdpLoadedOf, LdpSolverOf};

    /// [`LdpSolverOf`] with run-time sizes.
    pub type LdpSolverDyn = LdpSolverOf<Dyn, Dyn>;
    /// [`LdpLoadedOf`] with run-time sizes.
    pub type LdpLoadedDyn = LdpLoadedOf<Dyn, Dyn>;
}

#[cfg(feature = "alloc")]
pub use dynamic::{LdpLoadedDyn, LdpSolverDyn};

impl<NV: Dim, NC: Dim> LdpSolverOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The LDP form of the rows of `qp` (its `q` and `h` are not used) for the
    /// Hessian of `solver`. Non-finite rows, rows whose squared norms
    /// overflow, or a `qp` with another number of variables make every later
    /// solve a [`QpStatus::NumericalError`].
    pub fn prepare(solver: &DualActiveSetOf<NV, NC>, qp: &DenseQpOf<NV, NC>) -> Self {
        let (nv, nc) = qp.gt.shape_generic();
        let n = nv.value();
        let m = qp.m.min(nc.value());
        let tol = solver.settings().tol_primal;
        let rows = DenseQpOf {
            q: OVector::zeros_generic(nv, U1),
            gt: qp.gt.clone(),
            h: OVector::zeros_generic(nc, U1),
            m,
        };
        let mut p = LdpSolverOf {
            solver: solver.clone(),
            norms: solver.prepare_rows(&rows),
            qp: rows,
            mhat: OMatrix::zeros_generic(nv, nc),
            K: OMatrix::zeros_generic(nc, nc),
            inv_mnorm: OVector::zeros_generic(nc, U1),
            thr: OVector::zeros_generic(nc, U1),
            zero: OVector::from_element_generic(nc, U1, false),
            m,
            finite: solver.nv() == n,
        };
        let mhat = p.mhat.as_mut_slice();
        let (inv_mnorm, thr, zero) = (
            p.inv_mnorm.as_mut_slice(),
            p.thr.as_mut_slice(),
            p.zero.as_mut_slice(),
        );
        for (i, g) in columns(qp.gt.as_slice(), n).enumerate().take(m) {
            let n2 = dot(g, g);
            let mi = solver.linv_mul(g);
            let mn2 = dot(mi.as_slice(), mi.as_slice());
            if !(n2.is_finite() && mn2.is_finite()) {
                p.finite = false;
                continue;
            }
            if n2 <= ZERO_ROW2 || mn2 <= 0.0 {
                if let Some(z) = zero.get_mut(i) {
                    *z = true;
                }
                continue;
            }
            let inv = 1.0 / libm::sqrt(mn2);
            if let Some(col) = column_mut(mhat, n, i) {
                for (a, b) in col.iter_mut().zip(mi.iter()) {
                    *a = b * inv;
                }
            }
            if let (Some(a), Some(b)) = (inv_mnorm.get_mut(i), thr.get_mut(i)) {
                *a = inv;
                *b = tol * tol * n2 * inv * inv;
            }
        }
        let nck = nc.value();
        let K = p.K.as_mut_slice();
        for i in 0..m {
            for j in 0..=i {
                let k = match (column(mhat, n, i), column(mhat, n, j)) {
                    (Some(a), Some(b)) => dot(a, b),
                    _ => 0.0,
                };
                if let Some(e) = K.get_mut(j * nck + i) {
                    *e = k;
                }
                if let Some(e) = K.get_mut(i * nck + j) {
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
    /// ignored. Non-finite `q` or `h` (or a `q` or `h` of another length) make
    /// the solve a [`QpStatus::NumericalError`].
    pub fn load(&self, q: &OVector<f64, NV>, h: &OVector<f64, NC>) -> LdpLoadedOf<NV, NC> {
        let n = self.mhat.nrows();
        let tol = self.solver.settings().tol_primal;
        let v = self.solver.linv_mul(q.as_slice());
        let vv = dot(v.as_slice(), v.as_slice());
        let mut ld = LdpLoadedOf {
            q: q.clone(),
            h: h.clone(),
            v,
            vv,
            s0: OVector::zeros_generic(self.inv_mnorm.shape_generic().0, U1),
            zero_infeasible: None,
            m: self.m,
            finite: q.iter().all(|a| a.is_finite())
                && q.len() == n
                && h.len() == self.inv_mnorm.len(),
        };
        let vs = ld.v.as_slice();
        let mhat = self.mhat.as_slice();
        // Plain indices below a bound every slice visibly meets.
        let m = self
            .m
            .min(ld.s0.len())
            .min(self.zero.len())
            .min(self.inv_mnorm.len());
        let (s0, zero, inv_mnorm) = (
            &mut ld.s0.as_mut_slice()[..m],
            &self.zero.as_slice()[..m],
            &self.inv_mnorm.as_slice()[..m],
        );
        let hs = h.as_slice();
        for i in 0..m {
            let hi = hs.get(i).copied().unwrap_or(f64::NAN);
            if !hi.is_finite() {
                ld.finite = false;
            }
            if zero[i] {
                if hi < -tol && ld.zero_infeasible.is_none() {
                    ld.zero_infeasible = Some(i);
                }
                continue;
            }
            // d_i / |m_i| = h_i / |m_i| + mhat_i . v
            let mv = column(mhat, n, i).map_or(0.0, |mi| dot(mi, vs));
            s0[i] = hi * inv_mnorm[i] + mv;
        }
        ld
    }

    /// [`LdpSolverOf::load`] and [`LdpSolverOf::solve`] with `qp.q` and `qp.h`
    /// (`qp`'s rows must be the prepared ones; they are not read).
    pub fn solve_qp(
        &self,
        qp: &DenseQpOf<NV, NC>,
        prefer: &[bool],
        max_iter: u32,
    ) -> QpSolutionOf<NV, NC> {
        let ld = self.load(&qp.q, &qp.h);
        self.solve(&ld, prefer, max_iter)
    }

    /// Solves the loaded QP with at most `max_iter` adds plus drops; `prefer[i]`
    /// marks row `i` as expected active (warm start). Same contract as
    /// [`DualActiveSetOf::solve`]. A `loaded` from a solver with another row count
    /// gives [`QpStatus::NumericalError`].
    pub fn solve(
        &self,
        loaded: &LdpLoadedOf<NV, NC>,
        prefer: &[bool],
        max_iter: u32,
    ) -> QpSolutionOf<NV, NC> {
        let (nv, nc) = self.mhat.shape_generic();
        let n = nv.value();
        let m = self.m.min(nc.value());
        let mut sol = QpSolutionOf {
            x: OVector::zeros_generic(nv, U1),
            lambda: OVector::zeros_generic(nc, U1),
            objective: 0.0,
            status: QpStatus::NumericalError,
            iterations: 0,
            active: OVector::from_element_generic(nv, U1, 0),
            n_active: 0,
        };
        if !self.finite
            || !loaded.finite
            || loaded.m != self.m
            || loaded.s0.len() != nc.value()
            || m > usize::from(u16::MAX)
        {
            return sol;
        }
        if let Some(i) = loaded.zero_infeasible {
            // 0'x <= h with h < 0: y = e_i certifies it.
            sol.status = QpStatus::Infeasible;
            if let Some(y) = sol.lambda.as_mut_slice().get_mut(i) {
                *y = 1.0;
            }
            return sol;
        }
        let tol_dep = self.solver.settings().tol_dependence;
        let tol_dep2 = tol_dep * tol_dep;
        let nck = nc.value();
        let mhat = self.mhat.as_slice();
        let Kall = self.K.as_slice();
        let thr = self.thr.as_slice();
        let mut s = loaded.s0.clone(); // scaled slacks of all rows
        let mut blocked = self.zero.clone(); // active or zero rows: not scanned
        let mut lam = OVector::<f64, NV>::zeros_generic(nv, U1); // scaled multipliers
        let mut act = OVector::<u16, NV>::from_element_generic(nv, U1, 0);
        // Cholesky factor of M_A M_A' (scaled rows), row `i` stored as the
        // `i`-th chunk of `n`, zeros above the diagonal kept exactly zero (the
        // solves use full-length dots).
        let mut C = OMatrix::<f64, NV, NV>::zeros_generic(nv, nv);
        let mut Ci = OMatrix::<f64, NV, NV>::zeros_generic(nv, nv); // C^-1, lower triangular
        let mut b = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut w = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut r = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut w2 = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut r2 = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut z = OVector::<f64, NV>::zeros_generic(nv, U1);
        let (s, blocked, lam, act, C, Ci) = (
            s.as_mut_slice(),
            blocked.as_mut_slice(),
            lam.as_mut_slice(),
            act.as_mut_slice(),
            C.as_mut_slice(),
            Ci.as_mut_slice(),
        );
        let (b, w, r, w2, r2, z) = (
            b.as_mut_slice(),
            w.as_mut_slice(),
            r.as_mut_slice(),
            w2.as_mut_slice(),
            r2.as_mut_slice(),
            z.as_mut_slice(),
        );
        let mut nact: usize = 0;
        let mut iters: u32 = 0;
        // The row being added and its multiplier (part of the iterate).
        let mut pending: Option<(usize, f64)> = None;
        // On infeasibility: the row `p` whose `-r` (in `r`) certifies it.
        let mut farkas: Option<usize> = None;

        let status = 'outer: loop {
            // Step 1: the most violated row in the H^-1 metric (marked first).
            let mut best: Option<usize> = None;
            let mut best_v = 0.0;
            let mut best_pref: Option<usize> = None;
            let mut best_pref_v = 0.0;
            // Plain indices below a bound every slice visibly meets.
            let mm = m.min(s.len()).min(blocked.len()).min(thr.len());
            let (sv, bv, tv) = (&s[..mm], &blocked[..mm], &thr[..mm]);
            for i in 0..mm {
                let si = sv[i];
                if bv[i] || si >= 0.0 || si * si <= tv[i] {
                    continue;
                }
                if !si.is_finite() {
                    break 'outer QpStatus::NumericalError;
                }
                if si < best_v {
                    best_v = si;
                    best = Some(i);
                }
                if prefer.get(i).copied().unwrap_or(false) && si < best_pref_v {
                    best_pref_v = si;
                    best_pref = Some(i);
                }
            }
            let p = match best_pref.or(best) {
                None => break QpStatus::Solved,
                Some(p) => p,
            };
            let (Some(mp), Some(kp)) = (column(mhat, n, p), column(Kall, nck, p)) else {
                break QpStatus::NumericalError;
            };
            pending = Some((p, 0.0));
            let mut u_new = 0.0;

            // Step 2: move until p holds (full step) or a row must be dropped.
            loop {
                if iters >= max_iter {
                    break 'outer QpStatus::IterationLimit;
                }
                let nact_c = nact.min(n);
                // w = C^-1 M_A m_p, r = C^-T w = (M_A M_A')^-1 M_A m_p.
                b.fill(0.0);
                for (bi, &a) in b.iter_mut().zip(act.iter()).take(nact_c) {
                    *bi = kp.get(usize::from(a)).copied().unwrap_or(0.0);
                }
                chol_solve(Ci, n, b, nact_c, w, r);
                // z = m_p - M_A' r: the component of m_p outside the active span.
                copy_into(z, mp);
                sub_active(mhat, n, z, act, r, nact_c);
                let mut z2 = dot(z, z);
                if z2 < REFINE2 {
                    // Cancellation: z carries rounding of order eps cond(M_A)^2.
                    // Project it once more (Gram-Schmidt "twice is enough"),
                    // r2 = (M_A M_A')^-1 M_A z, z -= M_A' r2, r += r2.
                    b.fill(0.0);
                    for (bi, &a) in b.iter_mut().zip(act.iter()).take(nact_c) {
                        if let Some(ma) = column(mhat, n, usize::from(a)) {
                            *bi = dot(ma, z);
                        }
                    }
                    chol_solve(Ci, n, b, nact_c, w2, r2);
                    sub_active(mhat, n, z, act, r2, nact_c);
                    for (ri, r2i) in r.iter_mut().zip(r2.iter()) {
                        *ri += r2i;
                    }
                    for (wi, w2i) in w.iter_mut().zip(w2.iter()) {
                        *wi += w2i;
                    }
                    z2 = dot(z, z);
                }
                // Partial (dual) step length t1 and the row to drop.
                let mut t1 = f64::INFINITY;
                let mut drop: Option<usize> = None;
                let ra = r.get(..nact_c).unwrap_or(&[]);
                let rmax = ra.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                for (i, (&ri, &li)) in ra.iter().zip(lam.iter()).enumerate() {
                    if ri > 1e-14 * rmax.max(1.0) {
                        let t = li / ri;
                        if t < t1 {
                            t1 = t;
                            drop = Some(i);
                        }
                    }
                }
                // Full (primal) step length t2 (|mhat_p| = 1).
                // With NV rows active (independent) the span is everything.
                let dependent = z2 <= tol_dep2 || nact_c >= n;
                let sp = s.get(p).copied().unwrap_or(0.0);
                let t2 = if dependent { f64::INFINITY } else { -sp / z2 };
                if !(t1.is_finite() || t2.is_finite()) {
                    if t1.is_nan() || t2.is_nan() {
                        break 'outer QpStatus::NumericalError;
                    }
                    // m_p = M_A' r with every r_j <= 0: y_p = 1, y_A = -r.
                    farkas = Some(p);
                    break 'outer QpStatus::Infeasible;
                }
                let t = t1.min(t2);
                iters += 1;
                for (li, &ri) in lam.iter_mut().zip(r.iter()).take(nact_c) {
                    *li -= t * ri;
                }
                u_new += t;
                pending = Some((p, u_new));
                if !dependent {
                    // u moves by -t z: slack_i grows by t mhat_i . z
                    // = t (K_ip - sum_j r_j K_i,A_j).
                    let sm = s.get_mut(..m).unwrap_or(&mut []);
                    for (si, &k) in sm.iter_mut().zip(kp) {
                        *si += t * k;
                    }
                    for (&a, &rj) in act.iter().zip(r.iter()).take(nact_c) {
                        if let Some(ka) = column(Kall, nck, usize::from(a)) {
                            let f = t * rj;
                            for (si, &k) in sm.iter_mut().zip(ka) {
                                *si -= f * k;
                            }
                        }
                    }
                }
                if t2 <= t1 {
                    // Full step: p becomes active; C gains the row [w', |z|].
                    let diag = libm::sqrt(z2);
                    let (Some(row), Some(a), Some(l), Some(flag)) = (
                        column_mut(C, n, nact_c),
                        act.get_mut(nact_c),
                        lam.get_mut(nact_c),
                        blocked.get_mut(p),
                    ) else {
                        break 'outer QpStatus::NumericalError;
                    };
                    if !(diag > 0.0 && diag.is_finite()) {
                        break 'outer QpStatus::NumericalError;
                    }
                    if diag < PIVOT_FALLBACK {
                        // The normal equations would lose too much accuracy.
                        return self.fallback(loaded, prefer, max_iter);
                    }
                    copy_into(row, w);
                    if let Some(e) = row.get_mut(nact_c) {
                        *e = diag;
                    }
                    // C^-1 gains the row [-(C^-T w)' / |z|, 1 / |z|] = [-r', 1] / |z|.
                    if let Some(ci) = column_mut(Ci, n, nact_c) {
                        let inv = 1.0 / diag;
                        for (c, rk) in ci.iter_mut().zip(r.iter()) {
                            *c = -rk * inv;
                        }
                        if let Some(e) = ci.get_mut(nact_c) {
                            *e = inv;
                        }
                    }
                    *a = p as u16;
                    *l = u_new;
                    *flag = true;
                    if let Some(sp) = s.get_mut(p) {
                        *sp = 0.0;
                    }
                    nact = nact_c + 1;
                    pending = None;
                    continue 'outer;
                }
                // Partial step: drop active row `l`, then retry the same p.
                let Some((l, &row_l)) = drop.and_then(|l| Some((l, act.get(l)?))) else {
                    break 'outer QpStatus::NumericalError;
                };
                if let Some(flag) = blocked.get_mut(usize::from(row_l)) {
                    *flag = false;
                }
                chol_drop(C, Ci, nv, nact_c, l);
                let last = nact_c.saturating_sub(1);
                shift_down(act, l, last);
                shift_down(lam, l, last);
                if let Some(e) = lam.get_mut(last) {
                    *e = 0.0;
                }
                nact = last;
            }
        };

        let nact = nact.min(n);
        // u = -M_A' lambda_A - u_new m_p (scaled rows, scaled multipliers).
        let mut u = OVector::<f64, NV>::zeros_generic(nv, U1);
        let us = u.as_mut_slice();
        for (&a, &la) in act.iter().zip(lam.iter()).take(nact) {
            if let Some(ma) = column(mhat, n, usize::from(a)) {
                for (uk, mk) in us.iter_mut().zip(ma) {
                    *uk -= la * mk;
                }
            }
        }
        if let Some((p, un)) = pending
            && let Some(mp) = column(mhat, n, p)
        {
            for (uk, mk) in us.iter_mut().zip(mp) {
                *uk -= un * mk;
            }
        }
        let mut uv = u.clone();
        for (a, b) in uv.iter_mut().zip(loaded.v.iter()) {
            *a -= b;
        }
        sol.x = self.solver.linvt_mul(uv.as_slice());
        sol.objective = 0.5 * (dot(u.as_slice(), u.as_slice()) - loaded.vv);
        // Multipliers in the units of G: lambda_i = lambda_hat_i / |m_i|.
        let lambda = sol.lambda.as_mut_slice();
        let inv_mnorm = self.inv_mnorm.as_slice();
        match farkas {
            Some(p) => {
                let scale = inv_mnorm.get(p).copied().unwrap_or(1.0);
                if let Some(y) = lambda.get_mut(p) {
                    *y = 1.0;
                }
                for (&a, &rj) in act.iter().zip(r.iter()).take(nact) {
                    let a = usize::from(a);
                    let y = -rj;
                    if let (Some(l), Some(&inv)) = (lambda.get_mut(a), inv_mnorm.get(a)) {
                        *l = (y * inv / scale).max(0.0);
                    }
                }
            }
            None => {
                for (&a, &la) in act.iter().zip(lam.iter()).take(nact) {
                    let a = usize::from(a);
                    if let (Some(l), Some(&inv)) = (lambda.get_mut(a), inv_mnorm.get(a)) {
                        *l = (la * inv).max(0.0);
                    }
                }
            }
        }
        copy_into(sol.active.as_mut_slice(), act);
        sol.n_active = nact;
        sol.iterations = iters;
        sol.status = if sol.x.iter().all(|v| v.is_finite()) && sol.objective.is_finite() {
            status
        } else {
            QpStatus::NumericalError
        };
        sol
    }

    /// [`DualActiveSetOf::solve_prepared`] on the loaded QP: the answer for an
    /// active set too ill-conditioned for the normal equations of the LDP.
    #[cold]
    fn fallback(
        &self,
        loaded: &LdpLoadedOf<NV, NC>,
        prefer: &[bool],
        max_iter: u32,
    ) -> QpSolutionOf<NV, NC> {
        let mut qp = self.qp.clone();
        qp.q = loaded.q.clone();
        qp.h = loaded.h.clone();
        self.solver
            .solve_prepared(&qp, &self.norms, prefer, max_iter)
    }
}

/// `z -= M_A' r` over the first `nact` active rows (scaled rows, columns of
/// `mhat` with `n` entries each).
#[inline(always)]
fn sub_active(mhat: &[f64], n: usize, z: &mut [f64], act: &[u16], r: &[f64], nact: usize) {
    for (&a, &rj) in act.iter().zip(r).take(nact) {
        if let Some(ma) = column(mhat, n, usize::from(a)) {
            for (zk, mk) in z.iter_mut().zip(ma) {
                *zk -= rj * mk;
            }
        }
    }
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

/// Below this squared norm of the new row's component outside the active span
/// (the rows have unit norm: `|z| < 0.1`), the component is projected a second
/// time.
const REFINE2: f64 = 1e-2;

/// `w = C^-1 b`, `r = C^-T w = (C C')^-1 b` on the leading `nact x nact`
/// block, from the inverse factor `Ci = C^-1` (lower triangular, zeros above
/// the diagonal, row `i` the `i`-th chunk of `n`): two matrix-vector
/// products, no chain of dependent divisions or dot products as in
/// substitution. `w` and `r` are overwritten.
#[inline(always)]
fn chol_solve(Ci: &[f64], n: usize, b: &[f64], nact: usize, w: &mut [f64], r: &mut [f64]) {
    w.fill(0.0);
    for (wi, row) in w.iter_mut().zip(columns(Ci, n)).take(nact) {
        *wi = dot(row, b);
    }
    r.fill(0.0);
    for (&wi, row) in w.iter().zip(columns(Ci, n)).take(nact) {
        for (rk, c) in r.iter_mut().zip(row) {
            *rk += wi * c;
        }
    }
}

/// Removes row `l` (of `nact`) from the Cholesky factor `C` of `M_A M_A'`
/// (`n x n`, row `i` the `i`-th chunk of `n`): the rows below move up, and
/// Givens rotations of column pairs restore the triangle (`C C'` stays the
/// Gram matrix of the remaining rows). The rows `l..` of the inverse factor
/// `Ci` are then recomputed from `C Ci = I`.
#[inline]
fn chol_drop<NV: Dim>(C: &mut [f64], Ci: &mut [f64], nv: NV, nact: usize, l: usize) {
    let n = nv.value();
    let nact = nact.min(n);
    if l >= nact {
        return;
    }
    let last = nact - 1;
    for i in l..last {
        if let Some((head, tail)) = C.split_at_mut_checked((i + 1).saturating_mul(n))
            && let (Some(dst), Some(src)) = (head.get_mut(i * n..), tail.get(..n))
        {
            for (d, &s) in dst.iter_mut().zip(src) {
                *d = s;
            }
        }
    }
    if let Some(row) = column_mut(C, n, last) {
        row.fill(0.0);
    }
    if let Some(row) = column_mut(Ci, n, last) {
        row.fill(0.0);
    }
    // Rows k..last-1 now reach column k+1; rotate columns k, k+1.
    for k in l..last {
        let Some(rk) = column_mut(C, n, k) else {
            break;
        };
        let Some(&[a, b]) = rk.get(k..k + 2) else {
            break;
        };
        if b == 0.0 {
            continue;
        }
        let (c, s, r) = givens(a, b);
        if let Some([x, y]) = rk.get_mut(k..k + 2) {
            *x = r;
            *y = 0.0;
        }
        for row in columns_mut(C, n).take(last).skip(k + 1) {
            if let Some([x, y]) = row.get_mut(k..k + 2) {
                let (a, b) = (*x, *y);
                *x = c * a + s * b;
                *y = -s * a + c * b;
            }
        }
    }
    // Row i of C Ci = I: C_ii Ci_i = e_i - sum_{k<i} C_ik Ci_k.
    for i in l..last {
        let Some((above, rest)) = Ci.split_at_mut_checked(i.saturating_mul(n)) else {
            break;
        };
        let Some(row) = rest.get_mut(..n) else {
            break;
        };
        let Some(ci) = column(C, n, i) else {
            break;
        };
        row.fill(0.0);
        if let Some(e) = row.get_mut(i) {
            *e = 1.0;
        }
        for (&f, cik) in ci.iter().zip(columns(above, n)).take(i) {
            for (a, b) in row.iter_mut().zip(cik) {
                *a -= f * b;
            }
        }
        let inv = 1.0 / ci.get(i).copied().unwrap_or(0.0);
        for a in row.iter_mut() {
            *a *= inv;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::qp::{DenseQp, DualActiveSet, QpSettings, QpSolution};
    use nalgebra::SVector;
    use nalgebra::{Matrix2, SMatrix, Vector2};

    /// Deterministic uniform numbers in [-1, 1) (64-bit LCG).
    struct Rnd(u64);
    impl Rnd {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// Checks a Farkas certificate: y >= 0, |G'y| small, h'y < 0.
    fn assert_certificate<const NV: usize, const NC: usize>(
        qp: &DenseQp<NV, NC>,
        y: &SVector<f64, NC>,
    ) {
        let mut gty = SVector::<f64, NV>::zeros();
        let (mut hty, mut scale) = (0.0, 0.0f64);
        for (i, (g, h)) in qp.rows().enumerate() {
            assert!(y[i] >= 0.0);
            gty += g * y[i];
            hty += h * y[i];
            scale = scale.max(y[i] * g.amax());
        }
        assert!(gty.amax() <= 1e-10 * (1.0 + scale), "G'y = {gty:?}");
        assert!(hty < 0.0, "h'y = {hty}");
    }

    /// `(|G'y| / sum_i y_i |g_i|, h'y)` of a certificate `y >= 0`.
    fn certificate_residual<const NV: usize, const NC: usize>(
        qp: &DenseQp<NV, NC>,
        y: &SVector<f64, NC>,
    ) -> (f64, f64) {
        let mut gty = SVector::<f64, NV>::zeros();
        let (mut hty, mut scale) = (0.0, 0.0);
        for (i, (g, h)) in qp.rows().enumerate() {
            assert!(y[i] >= 0.0);
            gty += g * y[i];
            hty += h * y[i];
            scale += y[i] * g.norm();
        }
        (if scale > 0.0 { gty.norm() / scale } else { 0.0 }, hty)
    }

    /// KKT conditions of a solution (stationarity, feasibility,
    /// complementarity, signs), independent of either solver.
    fn assert_kkt<const NV: usize, const NC: usize>(
        s: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        sol: &QpSolution<NV, NC>,
    ) {
        let mut stat = s.hessian() * sol.x + qp.q;
        let scale = 1.0 + sol.lambda.amax() + qp.q.amax();
        for (i, (g, h)) in qp.rows().enumerate() {
            let slack = h - g.dot(&sol.x);
            assert!(sol.lambda[i] >= 0.0);
            assert!(
                slack >= -1e-9 * g.norm().max(1.0),
                "row {i} violated by {slack}"
            );
            assert!(
                (sol.lambda[i] * slack).abs() < 1e-9 * scale,
                "complementarity"
            );
            stat += g * sol.lambda[i];
        }
        assert!(stat.amax() < 1e-9 * scale, "stationarity {stat:?}");
    }

    /// The LDP path and `solve` on one QP: same status and iterations;
    /// solved: x, objective and multipliers agree and satisfy KKT;
    /// infeasible: both certificates are valid.
    fn assert_same<const NV: usize, const NC: usize>(
        s: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        prefer: &[bool; NC],
    ) -> QpStatus {
        let a = s.solve(qp, prefer, 500);
        let ldp = LdpSolver::prepare(s, qp);
        let b = ldp.solve_qp(qp, prefer, 500);
        assert_eq!(a.status, b.status, "{qp:?}");
        assert_eq!(a.iterations, b.iterations);
        match b.status {
            QpStatus::Solved => {
                assert_kkt(s, qp, &b);
                let xs = a.x.amax().max(1.0);
                assert!((a.x - b.x).amax() <= 1e-9 * xs, "{} vs {}", a.x, b.x);
                let os = a.objective.abs().max(1.0);
                assert!((a.objective - b.objective).abs() <= 1e-9 * os);
                let ls = a.lambda.amax().max(1.0);
                assert!((a.lambda - b.lambda).amax() <= 1e-8 * ls);
                assert_eq!(a.active_set(), b.active_set());
            }
            QpStatus::Infeasible => {
                assert_certificate(qp, &a.lambda);
                assert_certificate(qp, &b.lambda);
            }
            other => panic!("unexpected status {other:?}"),
        }
        b.status
    }

    fn random_hessian<const NV: usize>(rnd: &mut Rnd, diagonal: bool) -> SMatrix<f64, NV, NV> {
        if diagonal {
            SMatrix::from_diagonal(&SVector::from_fn(|_, _| 0.1 + 10.0 * rnd.next().abs()))
        } else {
            let A = SMatrix::<f64, NV, NV>::from_fn(|_, _| rnd.next());
            A.transpose() * A + SMatrix::identity() * 0.1
        }
    }

    fn random_family<const NV: usize, const NC: usize>(seed: u64, count: usize) {
        let mut rnd = Rnd(seed);
        let (mut solved, mut infeasible) = (0, 0);
        for k in 0..count {
            let H = random_hessian::<NV>(&mut rnd, k % 2 == 0);
            let s = DualActiveSet::<NV, NC>::new(&H, QpSettings::default()).unwrap();
            let mut qp = DenseQp::<NV, NC>::with_q(SVector::from_fn(|_, _| 5.0 * rnd.next()));
            for _ in 0..(4 + k % (NC - 3)) {
                let g = SVector::<f64, NV>::from_fn(|_, _| rnd.next());
                qp.push_row(&g, rnd.next() + 0.3).unwrap();
            }
            let mut prefer = [false; NC];
            if k % 3 == 0 {
                for p in prefer.iter_mut().take(qp.m) {
                    *p = rnd.next() > 0.5;
                }
            }
            match assert_same(&s, &qp, &prefer) {
                QpStatus::Solved => solved += 1,
                _ => infeasible += 1,
            }
        }
        assert!(
            solved > count / 4 && infeasible > count / 40,
            "{solved} solved, {infeasible} infeasible"
        );
    }

    #[test]
    fn agrees_with_solve_on_random_qps_n6() {
        random_family::<6, 24>(0x2545_f491_4f6c_dd1d, 600);
    }

    #[test]
    fn agrees_with_solve_on_random_qps_n16() {
        random_family::<16, 40>(0x9e37_79b9_7f4a_7c15, 300);
    }

    #[test]
    fn one_fixed_g_many_q_h() {
        // One preparation, many loads: every solve matches `solve`.
        let mut rnd = Rnd(7);
        let H = random_hessian::<6>(&mut rnd, false);
        let s = DualActiveSet::<6, 16>::new(&H, QpSettings::default()).unwrap();
        let mut qp = DenseQp::<6, 16>::default();
        for _ in 0..16 {
            let g = SVector::<f64, 6>::from_fn(|_, _| rnd.next());
            qp.push_row(&g, 0.0).unwrap();
        }
        let ldp = LdpSolver::prepare(&s, &qp);
        for _ in 0..200 {
            qp.q = SVector::from_fn(|_, _| 5.0 * rnd.next());
            qp.h = SVector::from_fn(|_, _| rnd.next() + 0.4);
            let a = s.solve(&qp, &[false; 16], 200);
            let b = ldp.solve(&ldp.load(&qp.q, &qp.h), &[false; 16], 200);
            assert_eq!(a.status, b.status);
            assert_eq!(a.iterations, b.iterations);
            assert!((a.x - b.x).amax() <= 1e-9 * a.x.amax().max(1.0));
        }
    }

    /// Random QPs built to be degenerate: duplicated, scaled, negated and
    /// nearly parallel rows, zero rows, rows through one point, scales from
    /// 1e-6 to 1e6. Every LDP result must be a valid solution or certificate
    /// (or IterationLimit/NumericalError only where `solve` says the same), and
    /// the status must match `solve`'s.
    fn degenerate_family<const NV: usize, const NC: usize>(seed: u64, count: usize) -> usize {
        let mut rnd = Rnd(seed);
        let mut same_iters = 0;
        for k in 0..count {
            let H = random_hessian::<NV>(&mut rnd, k % 3 == 0);
            let s = DualActiveSet::<NV, NC>::new(&H, QpSettings::default()).unwrap();
            let mut qp = DenseQp::<NV, NC>::with_q(SVector::from_fn(|_, _| 5.0 * rnd.next()));
            let x0 = SVector::<f64, NV>::from_fn(|_, _| rnd.next()); // a common point
            while qp.m < NC {
                let kind = (rnd.next().abs() * 7.0) as u32;
                let last = qp.m.checked_sub(1).map(|i| qp.get_row(i).unwrap());
                let (g, h) = match (kind, last) {
                    (0, Some((g, h))) => (g, h), // duplicate
                    (1, Some((g, h))) => {
                        let c = 10f64.powf(3.0 * rnd.next());
                        (g * c, h * c) // scaled copy
                    }
                    (2, Some((g, h))) => (-g, -h + 0.5 * rnd.next()), // opposite
                    (3, Some((g, h))) => {
                        let e = [1e-6, 1e-10, 1e-14][k % 3];
                        (g + SVector::from_fn(|_, _| e * rnd.next()), h) // nearly parallel
                    }
                    (4, _) => (SVector::zeros(), rnd.next() + 0.2), // zero row
                    (5, _) => {
                        let g = SVector::<f64, NV>::from_fn(|_, _| rnd.next());
                        let h = g.dot(&x0);
                        (g, h) // through x0
                    }
                    _ => {
                        let c = 10f64.powf(6.0 * rnd.next());
                        let g = SVector::<f64, NV>::from_fn(|_, _| c * rnd.next());
                        (g, c * (rnd.next() + 0.3))
                    }
                };
                qp.push_row(&g, h).unwrap();
            }
            let a = s.solve(&qp, &[false; NC], 500);
            let b = LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; NC], 500);
            assert_eq!(a.status, b.status, "case {k}");
            match b.status {
                QpStatus::Solved => {
                    let xs = a.x.amax().max(1.0);
                    assert!(
                        (a.x - b.x).amax() <= 1e-7 * xs,
                        "case {k}: {} vs {}",
                        a.x,
                        b.x
                    );
                }
                QpStatus::Infeasible => {
                    // With nearly parallel rows `solve`'s certificate can be
                    // inexact too: ours must be as good (to a factor 100).
                    let (ra, ha) = certificate_residual(&qp, &a.lambda);
                    let (rb, hb) = certificate_residual(&qp, &b.lambda);
                    assert!(rb <= (100.0 * ra).max(1e-10), "case {k}: {rb:e} vs {ra:e}");
                    assert!(hb < 0.0 || ha >= 0.0, "case {k}: h'y = {hb}");
                }
                _ => {}
            }
            same_iters += usize::from(a.iterations == b.iterations);
        }
        same_iters
    }

    #[test]
    fn degenerate_random_qps_match_solve() {
        let n6 = degenerate_family::<6, 24>(11, 400);
        let n16 = degenerate_family::<16, 40>(12, 200);
        // Rounding may change a tie between degenerate rows, so the paths may
        // differ now and then; nearly always they are the same.
        assert!(
            n6 >= 380 && n16 >= 190,
            "same iteration counts: {n6}/400, {n16}/200"
        );
    }

    fn solver2() -> DualActiveSet<2, 8> {
        DualActiveSet::new(&Matrix2::new(2.0, 0.0, 0.0, 2.0), QpSettings::default()).unwrap()
    }

    fn qp2(rows: &[([f64; 2], f64)]) -> DenseQp<2, 8> {
        let mut qp = DenseQp::<2, 8>::with_q(Vector2::new(-2.0, -4.0));
        for &(g, h) in rows {
            qp.push_row(&Vector2::from(g), h).unwrap();
        }
        qp
    }

    #[test]
    fn degenerate_rows() {
        let s = solver2();
        let dense =
            DualActiveSet::<2, 8>::new(&Matrix2::new(3.0, 1.0, 1.0, 2.0), QpSettings::default())
                .unwrap();
        let cases: [&[([f64; 2], f64)]; 8] = [
            // zero rows: satisfied, and one with h slightly negative but within tol
            &[([0.0, 0.0], 1.0), ([1.0, 1.0], 1.0), ([0.0, 0.0], -1e-12)],
            // duplicate rows (the second is linearly dependent once the first is active)
            &[([1.0, 1.0], 1.0), ([1.0, 1.0], 1.0), ([2.0, 2.0], 2.0)],
            // nearly parallel rows
            &[
                ([1.0, 1.0], 1.0),
                ([1.0, 1.0 + 1e-13], 1.0),
                ([1.0, 1.0 - 1e-9], 1.0),
            ],
            // three rows through the optimal vertex (degenerate vertex)
            &[
                ([1.0, 0.0], 0.0),
                ([0.0, 1.0], 0.0),
                ([1.0, 1.0], 0.0),
                ([1.0, 2.0], 0.0),
            ],
            // a drop is needed
            &[([1.0, 1.0], -2.0), ([0.0, 1.0], 0.0), ([1.0, 0.0], -1.0)],
            // infeasible: opposite half-planes, and parallel duplicates of them
            &[([1.0, 0.0], -1.0), ([-1.0, 0.0], -1.0), ([1.0, 0.0], -1.0)],
            // infeasible through a zero row with a negative right-hand side
            &[([1.0, 1.0], 1.0), ([0.0, 0.0], -1.0)],
            // infeasible triangle, one irrelevant row
            &[
                ([0.0, 1.0], 5.0),
                ([1.0, 1.0], -1.0),
                ([-1.0, 0.0], 0.0),
                ([0.0, -1.0], 0.0),
            ],
        ];
        for s in [&s, &dense] {
            for rows in cases {
                let qp = qp2(rows);
                assert_same(s, &qp, &[false; 8]);
                assert_same(s, &qp, &[true; 8]);
            }
        }
        let st: [QpStatus; 3] =
            [5, 6, 7].map(|k| assert_same(&solver2(), &qp2(cases[k]), &[false; 8]));
        assert!(st.iter().all(|s| s.is_infeasible()));
        // The zero-row certificate is e_1.
        let qp = qp2(cases[6]);
        let sol = LdpSolver::prepare(&solver2(), &qp).solve_qp(&qp, &[false; 8], 10);
        assert_eq!(sol.lambda[1], 1.0);
    }

    #[test]
    fn ill_conditioned_active_set_falls_back_to_solve() {
        // min |x - c|^2 with c = (1e6, 0.05) inside the thin cone of the
        // normals of x <= 0 and x + 1e-7 y <= 0: both are active at (0, 0).
        // The row added second has a component of 1e-7 < PIVOT_FALLBACK
        // outside the first, so the result is `solve_prepared`'s, bit for bit.
        let s = solver2();
        let mut qp = qp2(&[([1.0, 0.0], 0.0), ([1.0, 1e-7], 0.0)]);
        qp.q = Vector2::new(-2e6, -0.1);
        let a = s.solve(&qp, &[false; 8], 10);
        let b = LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8], 10);
        assert_eq!(a.status, QpStatus::Solved);
        assert_eq!((a.status, a.iterations), (b.status, b.iterations));
        assert_eq!(a.x, b.x);
        assert_eq!(a.lambda, b.lambda);
        assert_eq!(a.n_active, 2);
    }

    #[test]
    fn unconstrained_and_budget() {
        let s = solver2();
        let qp = qp2(&[]);
        let sol = LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8], 10);
        assert_eq!(sol.status, QpStatus::Solved);
        assert_eq!(sol.iterations, 0);
        assert!((sol.x - Vector2::new(1.0, 2.0)).amax() < 1e-14);
        assert!((sol.objective + 5.0).abs() < 1e-14);
        let qp = qp2(&[([1.0, 1.0], -2.0), ([0.0, 1.0], -1.0)]);
        let ldp = LdpSolver::prepare(&s, &qp);
        let full = ldp.solve_qp(&qp, &[false; 8], 10);
        assert_eq!((full.status, full.iterations), (QpStatus::Solved, 2));
        for budget in [0, 1] {
            let a = s.solve(&qp, &[false; 8], budget);
            let b = ldp.solve_qp(&qp, &[false; 8], budget);
            assert_eq!(b.status, QpStatus::IterationLimit);
            assert_eq!(b.iterations, budget);
            // The last iterate is the one of `solve`.
            assert!((a.x - b.x).amax() < 1e-12, "{} vs {}", a.x, b.x);
        }
    }

    #[test]
    fn bad_input_is_numerical_error() {
        let s = solver2();
        let good = qp2(&[([1.0, 1.0], 1.0)]);
        let ldp = LdpSolver::prepare(&s, &good);
        let err = |sol: QpSolution<2, 8>| assert_eq!(sol.status, QpStatus::NumericalError);
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            // q, h
            err(ldp.solve(&ldp.load(&Vector2::new(bad, 0.0), &good.h), &[false; 8], 10));
            let mut h = good.h;
            h[0] = bad;
            err(ldp.solve(&ldp.load(&good.q, &h), &[false; 8], 10));
            // G
            let qp = qp2(&[([1.0, bad], 1.0)]);
            err(LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8], 10));
        }
        // A row whose squared norm overflows.
        let qp = qp2(&[([1e200, 0.0], 1.0)]);
        err(LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8], 10));
        // Loaded data of a solver with another row count.
        let other = LdpSolver::prepare(&s, &qp2(&[([1.0, 0.0], 0.0), ([0.0, 1.0], 0.0)]));
        err(ldp.solve(&other.load(&good.q, &good.h), &[false; 8], 10));
        // The placeholder solver (H = 0): defined status, no panic.
        let ph = DualActiveSet::<2, 8>::PLACEHOLDER;
        let sol = LdpSolver::prepare(&ph, &good).solve_qp(&good, &[false; 8], 10);
        assert!(!sol.status.is_solved() || sol.x.iter().all(|v| v.is_finite()));
    }

    #[test]
    fn chol_drop_keeps_the_gram_matrix() {
        // Rows of a random 5 x 5 lower-triangular factor; drop each row in turn.
        let mut rnd = Rnd(3);
        for l in 0..5 {
            let mut C = [[0.0f64; 5]; 5];
            for (i, row) in C.iter_mut().enumerate() {
                for (j, c) in row.iter_mut().enumerate().take(i + 1) {
                    *c = if i == j {
                        1.0 + rnd.next().abs()
                    } else {
                        rnd.next()
                    };
                }
            }
            let gram = |C: &[[f64; 5]; 5], i: usize, j: usize| dot(&C[i], &C[j]);
            let before: [[f64; 5]; 5] =
                core::array::from_fn(|i| core::array::from_fn(|j| gram(&C, i, j)));
            // Ci = C^-1 by forward substitution, column by column.
            let mut Ci = [[0.0f64; 5]; 5];
            for j in 0..5 {
                for i in j..5 {
                    let mut acc = if i == j { 1.0 } else { 0.0 };
                    for k in j..i {
                        acc -= C[i][k] * Ci[k][j];
                    }
                    Ci[i][j] = acc / C[i][i];
                }
            }
            chol_drop(
                C.as_flattened_mut(),
                Ci.as_flattened_mut(),
                Const::<5>,
                5,
                l,
            );
            let keep: [usize; 4] = core::array::from_fn(|k| if k < l { k } else { k + 1 });
            for (a, &i) in keep.iter().enumerate() {
                assert!(C[a][a] > 0.0);
                for (b, &j) in keep.iter().enumerate() {
                    if b > a {
                        assert_eq!(C[a][b], 0.0, "upper triangle");
                        assert_eq!(Ci[a][b], 0.0, "upper triangle of the inverse");
                    }
                    assert!((gram(&C, a, b) - before[i][j]).abs() < 1e-12);
                    // (C Ci)_ab = delta_ab
                    let cci: f64 = (0..4).map(|k| C[a][k] * Ci[k][b]).sum();
                    assert!((cci - f64::from(u8::from(a == b))).abs() < 1e-12);
                }
            }
            assert_eq!(Ci[4], [0.0; 5]);
            assert_eq!(C[4], [0.0; 5]);
        }
    }
}
