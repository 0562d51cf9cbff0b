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
//! Memory: an [`LdpSolver`] holds `NC x NV` scaled rows and the `NC x NC` Gram
//! matrix (8 KiB for `NC = 32`, 113 KiB for `NC = 120`), so it is meant for
//! hosts or for small `NC`; the controller (whose `G` changes every cycle)
//! does not use it.
#![allow(non_snake_case)]

use nalgebra::SVector;

use crate::active_set::{self, ActiveSetFactor, AddError, dot, givens};
#[cfg(doc)]
use crate::qp::QpSettings;
use crate::qp::{DenseQp, DualActiveSet, QpSolution, QpStatus, RowNorms, ZERO_ROW2};

/// The least-distance form of one constraint matrix `G` for one Hessian: build
/// once with [`LdpSolver::prepare`], then [`LdpSolver::load`] and
/// [`LdpSolver::solve`] per `(q, h)`.
#[derive(Clone, Debug)]
pub struct LdpSolver<const NV: usize, const NC: usize> {
    /// The solver whose Hessian factor defines the change of variables.
    solver: DualActiveSet<NV, NC>,
    /// The rows of `G` (with `q = 0`, `h = 0`) and their norms, for the
    /// fallback to [`DualActiveSet::solve_prepared`] (see [`PIVOT_FALLBACK`]).
    qp: DenseQp<NV, NC>,
    /// Row norms of `qp` for the fallback.
    norms: RowNorms<NC>,
    /// `m_i / |m_i|` with `m_i = L^-1 g_i` (dimensionless; zero for zero rows).
    mhat: [[f64; NV]; NC],
    /// Gram matrix of the scaled rows, `K_ij = mhat_i . mhat_j` (unit diagonal
    /// for non-zero rows); rows `m..NC` are zero.
    K: [[f64; NC]; NC],
    /// `1 / |m_i|` (units of `1 / (G L^-T)`), 0 for zero rows.
    inv_mnorm: [f64; NC],
    /// Violation threshold on the squared scaled slack:
    /// `tol_primal^2 |g_i|^2 / |m_i|^2`.
    thr: [f64; NC],
    /// Row `i` is a zero row (`|g_i|^2` or `|m_i|^2` is 0): never added.
    zero: [bool; NC],
    /// Rows covered.
    m: usize,
    /// Every entry of `M` and `K` is finite.
    finite: bool,
}

/// The per-`(q, h)` data of an LDP solve, from [`LdpSolver::load`].
#[derive(Clone, Debug)]
pub struct LdpLoaded<const NV: usize, const NC: usize> {
    /// `q` and `h` as loaded, for the fallback.
    q: SVector<f64, NV>,
    /// Right-hand side `h` as loaded.
    h: SVector<f64, NC>,
    /// `v = L^-1 q`, so `x = L^-T (u - v)`.
    v: [f64; NV],
    /// `|v|^2`: the objective is `1/2 |u|^2 - 1/2 |v|^2`.
    vv: f64,
    /// Scaled slacks at `u = 0`: `d_i / |m_i| = (h_i - g_i x_unc) / |m_i|`
    /// with `x_unc = -H^-1 q` (0 for zero rows).
    s0: [f64; NC],
    /// A zero row with `h_i < -tol_primal` (the problem is infeasible).
    zero_infeasible: Option<usize>,
    /// Rows covered (must match the solver's).
    m: usize,
    /// `q` and `h` are finite.
    finite: bool,
}

impl<const NV: usize, const NC: usize> LdpSolver<NV, NC> {
    /// The LDP form of the rows of `qp` (its `q` and `h` are not used) for the
    /// Hessian of `solver`. Non-finite rows, or rows whose squared norms
    /// overflow, make every later solve a [`QpStatus::NumericalError`].
    pub fn prepare(solver: &DualActiveSet<NV, NC>, qp: &DenseQp<NV, NC>) -> Self {
        let m = qp.m.min(NC);
        let tol = solver.settings().tol_primal;
        let rows = DenseQp::<NV, NC> {
            gt: qp.gt,
            m,
            ..DenseQp::default()
        };
        let mut p = LdpSolver {
            // The LDP iterations have no hot start (module docs): its
            // fallback solves cold too, so both take the same path.
            solver: solver.without_hot_start(),
            norms: solver.prepare_rows(&rows),
            qp: rows,
            mhat: [[0.0; NV]; NC],
            K: [[0.0; NC]; NC],
            inv_mnorm: [0.0; NC],
            thr: [0.0; NC],
            zero: [false; NC],
            m,
            finite: true,
        };
        for (i, g) in qp.gt.data.0.iter().enumerate().take(m) {
            let n2 = dot(g, g);
            let mi = solver.linv_mul(g);
            let mn2 = dot(&mi, &mi);
            if !(n2.is_finite() && mn2.is_finite()) {
                p.finite = false;
                continue;
            }
            if n2 <= ZERO_ROW2 || mn2 <= 0.0 {
                p.zero[i] = true;
                continue;
            }
            let inv = 1.0 / libm::sqrt(mn2);
            for (a, b) in p.mhat[i].iter_mut().zip(&mi) {
                *a = b * inv;
            }
            p.inv_mnorm[i] = inv;
            p.thr[i] = tol * tol * n2 * inv * inv;
        }
        for i in 0..m {
            for j in 0..=i {
                let k = dot(&p.mhat[i], &p.mhat[j]);
                p.K[i][j] = k;
                p.K[j][i] = k;
            }
        }
        p
    }

    /// The solver this LDP was prepared for.
    pub fn solver(&self) -> &DualActiveSet<NV, NC> {
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
    pub fn load(&self, q: &SVector<f64, NV>, h: &SVector<f64, NC>) -> LdpLoaded<NV, NC> {
        let (qv, hv) = (*q, *h);
        let q = &q.data.0[0];
        let h = h.as_slice();
        let tol = self.solver.settings().tol_primal;
        let v = self.solver.linv_mul(q);
        let mut ld = LdpLoaded {
            q: qv,
            h: hv,
            v,
            vv: dot(&v, &v),
            s0: [0.0; NC],
            zero_infeasible: None,
            m: self.m,
            finite: q.iter().all(|a| a.is_finite()),
        };
        for i in 0..self.m.min(NC) {
            let hi = h[i];
            if !hi.is_finite() {
                ld.finite = false;
            }
            if self.zero[i] {
                if hi < -tol && ld.zero_infeasible.is_none() {
                    ld.zero_infeasible = Some(i);
                }
                continue;
            }
            // d_i / |m_i| = h_i / |m_i| + mhat_i . v
            ld.s0[i] = hi * self.inv_mnorm[i] + dot(&self.mhat[i], &v);
        }
        ld
    }

    /// [`LdpSolver::load`] and [`LdpSolver::solve`] with `qp.q` and `qp.h`
    /// (`qp`'s rows must be the prepared ones; they are not read).
    pub fn solve_qp(
        &self,
        qp: &DenseQp<NV, NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        let ld = self.load(&qp.q, &qp.h);
        self.solve(&ld, prefer, max_iter)
    }

    /// Solves the loaded QP with at most `max_iter` adds plus drops; `prefer[i]`
    /// marks row `i` as expected active (warm start). Same contract as
    /// [`DualActiveSet::solve`]. A `loaded` from a solver with another row count
    /// gives [`QpStatus::NumericalError`].
    pub fn solve(
        &self,
        loaded: &LdpLoaded<NV, NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        if !self.finite || !loaded.finite || loaded.m != self.m {
            return active_set::stopped(QpStatus::NumericalError, None);
        }
        if loaded.zero_infeasible.is_some() {
            // 0'x <= h with h < 0: y = e_i certifies it.
            return active_set::stopped(QpStatus::Infeasible, loaded.zero_infeasible);
        }
        let tol_dep = self.solver.settings().tol_dependence;
        let (mut C, mut Ci) = ([[0.0; NV]; NV], [[0.0; NV]; NV]);
        let mut factor = Gram {
            ldp: self,
            s: loaded.s0,
            C: &mut C,
            Ci: &mut Ci,
            tol_dep2: tol_dep * tol_dep,
            w: [0.0; NV],
            z2: 0.0,
            dependent: false,
        };
        // Zero rows are never added: they start (and stay) blocked.
        // No hot start (module docs): `hot` is false.
        let Some(it) = active_set::iterate(&mut factor, self.m, self.zero, prefer, max_iter, false)
        else {
            // The normal equations would lose too much accuracy.
            return self.fallback(loaded, prefer, max_iter);
        };
        // u = -M_A' lambda_A - u_new m_p (scaled rows, scaled multipliers).
        let mut u = [0.0f64; NV];
        for (&a, &la) in it.act.iter().zip(&it.mult).take(it.nact) {
            if let Some(ma) = self.mhat.get(usize::from(a)) {
                for (uk, mk) in u.iter_mut().zip(ma) {
                    *uk -= la * mk;
                }
            }
        }
        if let Some((p, un)) = it.adding
            && let Some(mp) = self.mhat.get(p)
        {
            for (uk, mk) in u.iter_mut().zip(mp) {
                *uk -= un * mk;
            }
        }
        let mut uv = u;
        for (a, b) in uv.iter_mut().zip(&loaded.v) {
            *a -= b;
        }
        let x = self.solver.linvt_mul(&uv);
        let objective = 0.5 * (dot(&u, &u) - loaded.vv);
        // Multipliers in the units of G: lambda_i = lambda_hat_i / |m_i|.
        it.solution(x, objective, |i| {
            self.inv_mnorm.get(i).copied().unwrap_or(1.0)
        })
    }

    /// [`DualActiveSet::solve_prepared`] on the loaded QP: the answer for an
    /// active set too ill-conditioned for the normal equations of the LDP.
    #[cold]
    fn fallback(
        &self,
        loaded: &LdpLoaded<NV, NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        let mut qp = self.qp.clone();
        qp.q = loaded.q;
        qp.h = loaded.h;
        self.solver
            .solve_prepared(&qp, &self.norms, prefer, max_iter)
    }

    /// `z -= M_A' r` over the first `nact` active rows (scaled rows).
    #[inline(always)]
    fn sub_active(&self, z: &mut [f64; NV], act: &[u16; NV], r: &[f64; NV], nact: usize) {
        for (&a, &rj) in act.iter().zip(r).take(nact) {
            if let Some(ma) = self.mhat.get(usize::from(a)) {
                for (zk, mk) in z.iter_mut().zip(ma) {
                    *zk -= rj * mk;
                }
            }
        }
    }
}

/// The active set of [`LdpSolver::solve`]: the Cholesky factor `C` of
/// `M_A M_A'` (scaled rows) and its inverse, with the scaled slacks of all
/// rows standing for the primal iterate `u`. The iteration itself is
/// [`crate::active_set::iterate`].
struct Gram<'a, const NV: usize, const NC: usize> {
    /// The prepared rows, their Gram matrix and thresholds.
    ldp: &'a LdpSolver<NV, NC>,
    /// Scaled slacks `(d_i - m_i u) / |m_i|` of all rows.
    s: [f64; NC],
    /// Cholesky factor of `M_A M_A'`, row-major, zeros above the diagonal kept
    /// exactly zero (the solves use full-length dots). The factors are the
    /// caller's locals: their addresses go to [`chol_drop`], and an escaping
    /// field would keep every other field of this struct in memory.
    C: &'a mut [[f64; NV]; NV],
    /// `C^-1`, lower triangular.
    Ci: &'a mut [[f64; NV]; NV],
    /// `tol_dependence^2`.
    tol_dep2: f64,
    /// `w = C^-1 M_A m_p` of the last direction: the new row of `C`.
    w: [f64; NV],
    /// `|z|^2`, `z = m_p - M_A' r` the component of the last row outside the
    /// active span.
    z2: f64,
    /// The last row was linearly dependent on the active rows.
    dependent: bool,
}

impl<const NV: usize, const NC: usize> ActiveSetFactor<NV> for Gram<'_, NV, NC> {
    #[inline(always)]
    fn violation(&mut self, i: usize, blocked: bool) -> Option<f64> {
        let (Some(&si), Some(&thr)) = (self.s.get(i), self.ldp.thr.get(i)) else {
            return None;
        };
        if si >= 0.0 || blocked || si * si <= thr {
            return None;
        }
        Some(if si.is_finite() { si } else { f64::NAN })
    }

    #[inline(always)]
    fn direction(
        &mut self,
        p: usize,
        act: &[u16; NV],
        nact: usize,
        r: &mut [f64; NV],
    ) -> Option<f64> {
        let ldp = self.ldp;
        let (Some(mp), Some(kp), Some(&sp)) = (ldp.mhat.get(p), ldp.K.get(p), self.s.get(p)) else {
            return None;
        };
        // w = C^-1 M_A m_p, r = C^-T w = (M_A M_A')^-1 M_A m_p.
        let mut b = [0.0f64; NV];
        for (bi, &a) in b.iter_mut().zip(act).take(nact) {
            *bi = kp.get(usize::from(a)).copied().unwrap_or(0.0);
        }
        // Zero beyond `nact`: `w` becomes a row of the triangle `C`.
        self.w = [0.0; NV];
        chol_solve(self.Ci, &b, nact, &mut self.w, r);
        // z = m_p - M_A' r: the component of m_p outside the active span.
        let mut z = *mp;
        ldp.sub_active(&mut z, act, r, nact);
        let mut z2 = dot(&z, &z);
        if z2 < REFINE2 {
            // Cancellation: z carries rounding of order eps cond(M_A)^2.
            // Project it once more (Gram-Schmidt "twice is enough"),
            // r2 = (M_A M_A')^-1 M_A z, z -= M_A' r2, r += r2.
            let mut b = [0.0f64; NV];
            for (bi, &a) in b.iter_mut().zip(act).take(nact) {
                if let Some(ma) = ldp.mhat.get(usize::from(a)) {
                    *bi = dot(ma, &z);
                }
            }
            let (mut w2, mut r2) = ([0.0f64; NV], [0.0f64; NV]);
            chol_solve(self.Ci, &b, nact, &mut w2, &mut r2);
            ldp.sub_active(&mut z, act, &r2, nact);
            for (ri, r2i) in r.iter_mut().zip(&r2) {
                *ri += r2i;
            }
            for (wi, w2i) in self.w.iter_mut().zip(&w2) {
                *wi += w2i;
            }
            z2 = dot(&z, &z);
        }
        // Full (primal) step length t2 (|mhat_p| = 1).
        // With NV rows active (independent) the span is everything.
        let dependent = z2 <= self.tol_dep2 || nact >= NV;
        let t2 = if dependent { f64::INFINITY } else { -sp / z2 };
        self.z2 = z2;
        self.dependent = dependent;
        Some(t2)
    }

    #[inline(always)]
    fn advance(&mut self, p: usize, t: f64, r: &[f64; NV], act: &[u16; NV], nact: usize) {
        let m = self.ldp.m.min(NC);
        let (false, Some(kp)) = (self.dependent, self.ldp.K.get(p)) else {
            return;
        };
        // u moves by -t z: slack_i grows by t mhat_i . z
        // = t (K_ip - sum_j r_j K_i,A_j).
        for (si, &k) in self.s[..m].iter_mut().zip(&kp[..m]) {
            *si += t * k;
        }
        for (&a, &rj) in act.iter().zip(r).take(nact) {
            if let Some(ka) = self.ldp.K.get(usize::from(a)) {
                let f = t * rj;
                for (si, &k) in self.s[..m].iter_mut().zip(&ka[..m]) {
                    *si -= f * k;
                }
            }
        }
    }

    /// Appends the row `[w', |z|]` to `C` and `[-r', 1] / |z|` to `C^-1`;
    /// asks for a restart when `|z| <` [`PIVOT_FALLBACK`].
    #[inline(always)]
    fn add(&mut self, p: usize, r: &[f64; NV], nact: usize) -> Result<(), AddError> {
        let diag = libm::sqrt(self.z2);
        let Some(row) = self.C.get_mut(nact) else {
            return Err(AddError::Numerical);
        };
        if !(diag > 0.0 && diag.is_finite()) {
            return Err(AddError::Numerical);
        }
        if diag < PIVOT_FALLBACK {
            return Err(AddError::Restart);
        }
        *row = self.w;
        row[nact] = diag;
        // C^-1 gains the row [-(C^-T w)' / |z|, 1 / |z|] = [-r', 1] / |z|.
        if let Some(ci) = self.Ci.get_mut(nact) {
            let inv = 1.0 / diag;
            for (c, rk) in ci.iter_mut().zip(r) {
                *c = -rk * inv;
            }
            ci[nact] = inv;
        }
        if let Some(sp) = self.s.get_mut(p) {
            *sp = 0.0;
        }
        Ok(())
    }

    #[inline(always)]
    fn drop(&mut self, l: usize, nact: usize) {
        chol_drop(self.C, self.Ci, nact, l);
    }
}

/// A row whose component outside the span of the active rows is shorter than
/// this (relative; the rows have unit norm), i.e. a row at an angle below
/// about 1e-6 rad from that span yet not linearly dependent to
/// `tol_dependence`, makes `M_A M_A'` too ill-conditioned (condition number
/// above 1e12, so the normal equations lose all but a few digits): the solve
/// restarts with [`DualActiveSet::solve_prepared`] on the same data, which
/// works with an orthogonal factor. Rare: not on the LIPMWALK set or the
/// controller's exported QPs (see `docs/solvers.md`).
pub const PIVOT_FALLBACK: f64 = 1e-6;

/// Below this squared norm of the new row's component outside the active span
/// (the rows have unit norm: `|z| < 0.1`), the component is projected a second
/// time.
const REFINE2: f64 = 1e-2;

/// `w = C^-1 b` and `r = C^-T w = (C C')^-1 b` on the leading `nact x nact`
/// block, from the inverse factor `Ci = C^-1` (lower triangular, zeros above
/// the diagonal): two matrix-vector products, no chain of dependent
/// divisions or dot products as in substitution. `r` must come zeroed;
/// entries `nact..` of `w` are left as they are.
#[inline(always)]
fn chol_solve<const NV: usize>(
    Ci: &[[f64; NV]; NV],
    b: &[f64; NV],
    nact: usize,
    w: &mut [f64; NV],
    r: &mut [f64; NV],
) {
    for (wi, row) in w.iter_mut().zip(Ci).take(nact) {
        *wi = dot(row, b);
    }
    for (&wi, row) in w.iter().zip(Ci).take(nact) {
        for (rk, c) in r.iter_mut().zip(row) {
            *rk += wi * c;
        }
    }
}

/// Removes row `l` (of `nact`) from the Cholesky factor `C` of `M_A M_A'`:
/// the rows below move up, and Givens rotations of column pairs restore the
/// triangle (`C C'` stays the Gram matrix of the remaining rows). The rows
/// `l..` of the inverse factor `Ci` are then recomputed from `C Ci = I`.
fn chol_drop<const NV: usize>(
    C: &mut [[f64; NV]; NV],
    Ci: &mut [[f64; NV]; NV],
    nact: usize,
    l: usize,
) {
    let nact = nact.min(NV);
    if l >= nact {
        return;
    }
    let last = nact - 1;
    // Checked access (the optimiser does not prove `i + 1 < NV` on every
    // target, see nopanic/); always in bounds.
    for i in l..last {
        if let Some(&next) = C.get(i + 1)
            && let Some(row) = C.get_mut(i)
        {
            *row = next;
        }
    }
    C[last] = [0.0; NV];
    Ci[last] = [0.0; NV];
    // Rows k..last-1 now reach column k+1; rotate columns k, k+1.
    for k in l..last {
        let (a, b) = (C[k][k], C[k][k + 1]);
        if b == 0.0 {
            continue;
        }
        let (c, s, r) = givens(a, b);
        C[k][k] = r;
        C[k][k + 1] = 0.0;
        for row in C.iter_mut().take(last).skip(k + 1) {
            let (a, b) = (row[k], row[k + 1]);
            row[k] = c * a + s * b;
            row[k + 1] = -s * a + c * b;
        }
    }
    // Row i of C Ci = I: C_ii Ci_i = e_i - sum_{k<i} C_ik Ci_k.
    for i in l..last {
        let mut row = [0.0f64; NV];
        row[i] = 1.0;
        for k in 0..i {
            let f = C[i][k];
            for (a, b) in row.iter_mut().zip(&Ci[k]) {
                *a -= f * b;
            }
        }
        let inv = 1.0 / C[i][i];
        for a in row.iter_mut() {
            *a *= inv;
        }
        Ci[i] = row;
    }
}

#[cfg(test)]
mod tests;
