//! The active set of [`DualActiveSet::solve`] as Goldfarb and Idnani keep it:
//! `J = L^-T Q` and the upper-triangular `R` of `L^-1 N_A = Q [R; 0]`, with
//! the primal iterate `x`; one Householder reflection per add, Givens
//! rotations per drop (no re-factorisation, no normal equations). The
//! iteration itself is [`crate::active_set::iterate`].

use nalgebra::SMatrix;

use super::{DualActiveSet, ZERO_ROW2};
use crate::active_set::{ActiveSetFactor, AddError, dot, givens};

/// The orthogonal factor of the active set, the iterate and the rows, for one
/// solve.
pub(super) struct Orthogonal<'a, const NV: usize, const NC: usize> {
    /// The solver (for `L^-1`, the tolerances and the `H^-1` row norms).
    pub solver: &'a DualActiveSet<NV, NC>,
    /// `rows[i]` is row `i` of `G`.
    pub rows: &'a [[f64; NV]; NC],
    /// Right-hand side.
    pub h: &'a [f64; NC],
    /// `|g_i|^2`.
    pub norm2: &'a [f64; NC],
    /// `1 / |L^-1 g_i|`, filled on demand (0 = not computed yet).
    pub inv_hnorm: &'a mut [f64; NC],
    /// `tol_primal^2`: a row is violated when `slack < 0` and
    /// `slack^2 > tol2 |g_i|^2`.
    pub tol2: f64,
    /// The primal iterate.
    pub x: [f64; NV],
    /// `J = L^-T Q`: columns `0..nact` span the active normals in the metric
    /// of `H^-1`, the others their complement. (The factors are the caller's
    /// locals, not fields: their addresses go to the add and drop, which the
    /// compiler may leave out of line, and an escaping field would keep every
    /// other field of this struct in memory.)
    pub J: &'a mut SMatrix<f64, NV, NV>,
    /// Upper-triangular `R` (leading `nact x nact` block).
    pub R: &'a mut SMatrix<f64, NV, NV>,
    /// `d = J' n_p` of the last direction (`n_p = -g_p`; the caller's
    /// local, as `J`).
    pub d: &'a mut [f64; NV],
    /// The primal step direction of the last direction (the caller's local).
    pub z: &'a mut [f64; NV],
    /// The last row `p` was linearly dependent on the active rows.
    pub dependent: bool,
}

impl<const NV: usize, const NC: usize> ActiveSetFactor<NV> for Orthogonal<'_, NV, NC> {
    // Row norms: Euclidean for the scale-free violation test, and in the
    // metric of H^-1 (|J0' g_i| = |L^-1 g_i|) for choosing which row to add:
    // `s_i / |L^-1 g_i|` is the square root of the cost increase of enforcing
    // row i alone, which picks rows that matter and roughly halves the
    // add/drop count on the controller's QPs compared with the Euclidean rule.
    // A row is violated when `slack / |g| < -tol`, tested without the square
    // root as `slack < 0` and `slack^2 > tol^2 |g|^2`.
    #[inline(always)]
    fn violation(&mut self, i: usize, blocked: bool) -> Option<f64> {
        let (Some(g), Some(&hi), Some(&n2), Some(ihn)) = (
            self.rows.get(i),
            self.h.get(i),
            self.norm2.get(i),
            self.inv_hnorm.get_mut(i),
        ) else {
            return None;
        };
        if blocked || n2 <= ZERO_ROW2 {
            return None;
        }
        let slack = hi - dot(g, &self.x);
        if !slack.is_finite() {
            return Some(f64::NAN);
        }
        if slack >= 0.0 || slack * slack <= self.tol2 * n2 {
            return None; // satisfied to tolerance
        }
        if *ihn == 0.0 {
            *ihn = self.solver.inv_hnorm(g, n2);
        }
        // Not NaN: `slack` is finite and `*ihn` positive (possibly infinite).
        Some(slack * *ihn)
    }

    #[inline(always)]
    fn direction(
        &mut self,
        p: usize,
        _act: &[u16; NV],
        nact: usize,
        r: &mut [f64; NV],
    ) -> Option<f64> {
        let (Some(gp), Some(&hp)) = (self.rows.get(p), self.h.get(p)) else {
            return None;
        };
        // d = J' n_p with the GI normal n_p = -g_p (n_p'x >= -h_p).
        let d = &mut *self.d;
        for (dj, col) in d.iter_mut().zip(&self.J.data.0) {
            *dj = -dot(col, gp);
        }
        // z = J2 d2: component of the step outside the active span.
        let z = &mut *self.z;
        *z = [0.0; NV];
        let mut d2sq = 0.0;
        for (col, &dj) in self.J.data.0.iter().zip(d.iter()).skip(nact) {
            for (zk, c) in z.iter_mut().zip(col) {
                *zk += c * dj; // column j of J, j >= nact
            }
            d2sq += dj * dj;
        }
        back_substitute(self.R, d, nact, r);
        // Full (primal) step length t2.
        let dn = crate::float::sqrt(dot(d, d));
        let dependent = crate::float::sqrt(d2sq) <= self.solver.settings.tol_dependence * dn;
        let slack_p = hp - dot(gp, &self.x); // < 0 while violated
        let t2 = if dependent {
            f64::INFINITY
        } else {
            -slack_p / d2sq
        };
        self.dependent = dependent;
        Some(t2)
    }

    #[inline(always)]
    fn advance(&mut self, _p: usize, t: f64, _r: &[f64; NV], _act: &[u16; NV], _nact: usize) {
        if !self.dependent {
            for (xk, zk) in self.x.iter_mut().zip(self.z.iter()) {
                *xk += t * zk;
            }
        }
    }

    /// Adds row `p` (see [`householder_add`]).
    #[inline(always)]
    fn add(&mut self, _p: usize, _r: &[f64; NV], nact: usize) -> Result<(), AddError> {
        if householder_add(self.J, self.R, nact, self.d) {
            Ok(())
        } else {
            Err(AddError::Numerical)
        }
    }

    /// Removes active row `l` (see [`givens_drop`]).
    #[inline(always)]
    fn drop(&mut self, l: usize, nact: usize) {
        givens_drop(self.J, self.R, nact, l);
    }

    const HOT_START: bool = NV >= super::HOT_START_MIN_NV;

    /// On the normal equations of the marked rows: `M = G_A L^-T` (rows
    /// `m_j = L^-1 g_j`), `K = M M'` by Cholesky (a pivot below `1e-10` of its
    /// diagonal entry, i.e. nearly dependent rows, gives up),
    /// `K lambda = G_A x0 - h_A`, `x = x0 - L^-T M' lambda`; then one pass
    /// over all rows. Cheaper than the adds of `J` and `R` (`O(k^2 NV)`
    /// against `O(k NV^2)`), which are only needed if an iteration follows.
    fn hot_guess(
        &mut self,
        act: &[u16; NV],
        k: usize,
        mult: &mut [f64; NV],
        blocked: &[bool],
    ) -> bool {
        let k = k.min(NV);
        let mut M = [[0.0f64; NV]; NV]; // rows 0..k: m_j
        let mut c = [0.0f64; NV];
        for j in 0..k {
            let a = usize::from(act[j]);
            let (Some(g), Some(&ha)) = (self.rows.get(a), self.h.get(a)) else {
                return false;
            };
            M[j] = self.solver.linv_mul(g);
            c[j] = dot(g, &self.x) - ha;
        }
        // K = C C' (lower C, row-major in `C[i][j]`, j <= i). Checked access
        // throughout (nopanic/: the optimiser does not see every bound).
        let at = |C: &[[f64; NV]; NV], i: usize, j: usize| {
            C.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0)
        };
        let mut C = [[0.0f64; NV]; NV];
        for i in 0..k {
            for j in 0..=i {
                let (Some(mi), Some(mj)) = (M.get(i), M.get(j)) else {
                    return false;
                };
                let mut s = dot(mi, mj);
                for l in 0..j {
                    s -= at(&C, i, l) * at(&C, j, l);
                }
                let v = if i == j {
                    if s.is_nan() || s <= 1e-10 * dot(mi, mi) {
                        return false;
                    }
                    crate::float::sqrt(s)
                } else {
                    s / at(&C, j, j)
                };
                if let Some(cij) = C.get_mut(i).and_then(|r| r.get_mut(j)) {
                    *cij = v;
                }
            }
        }
        // C y = c, C' lambda = y.
        let mut y = [0.0f64; NV];
        for i in 0..k {
            let mut s = c.get(i).copied().unwrap_or(0.0);
            for l in 0..i {
                s -= at(&C, i, l) * y.get(l).copied().unwrap_or(0.0);
            }
            if let Some(yi) = y.get_mut(i) {
                *yi = s / at(&C, i, i);
            }
        }
        let mut lambda = [0.0f64; NV];
        for i in (0..k).rev() {
            let mut s = y.get(i).copied().unwrap_or(0.0);
            for l in (i + 1)..k {
                s -= at(&C, l, i) * lambda.get(l).copied().unwrap_or(0.0);
            }
            if let Some(li) = lambda.get_mut(i) {
                *li = s / at(&C, i, i);
            }
        }
        if !lambda.iter().all(|&l| l >= 0.0 && l.is_finite()) {
            return false;
        }
        // x = x0 - L^-T M' lambda.
        let mut w = [0.0f64; NV];
        for (row, &l) in M.iter().zip(&lambda).take(k) {
            for (wk, &mk) in w.iter_mut().zip(row) {
                *wk += l * mk;
            }
        }
        let step = self.solver.linvt_mul(&w);
        let x0 = self.x;
        for (xk, sk) in self.x.iter_mut().zip(&step) {
            *xk -= sk;
        }
        // Every row must hold (the marked ones do, to rounding; if rounding
        // says otherwise the guess is dropped).
        let mut holds = true;
        for (i, &b) in blocked.iter().enumerate().take(NC) {
            if self.violation(i, b).is_some() {
                holds = false;
                break;
            }
        }
        if !holds || !self.x.iter().all(|v| v.is_finite()) {
            self.x = x0;
            return false;
        }
        *mult = lambda;
        true
    }

    /// `d = J' n_p`, then the add of [`householder_add`] unless the part of
    /// `d` outside the active span is below `tol_dependence |d|`.
    fn hot_add(&mut self, p: usize, nact: usize) -> Result<bool, AddError> {
        let Some(gp) = self.rows.get(p) else {
            return Err(AddError::Numerical);
        };
        let d = &mut *self.d;
        for (dj, col) in d.iter_mut().zip(&self.J.data.0) {
            *dj = -dot(col, gp);
        }
        let mut d2sq = 0.0;
        for &dj in d.iter().skip(nact) {
            d2sq += dj * dj;
        }
        let outside = crate::float::sqrt(d2sq);
        let dn = crate::float::sqrt(dot(d, d));
        if outside.is_nan() || outside <= self.solver.settings.tol_dependence * dn {
            return Ok(false);
        }
        if householder_add(self.J, self.R, nact, self.d) {
            Ok(true)
        } else {
            Err(AddError::Numerical)
        }
    }

    /// With the active normals `N = [-g_a]` (`J' N = [R; 0]`) and `x` the
    /// unconstrained minimiser: `R' w = c`, `c_j = g_j'x - h_j` (forward
    /// substitution; `w` kept in `d`), and `mult = R^-1 w`; the minimiser on
    /// the active rows is `x + J1 w` ([`ActiveSetFactor::hot_move`]).
    fn hot_multipliers(&mut self, act: &[u16; NV], nact: usize, mult: &mut [f64; NV]) -> bool {
        let n = nact.min(NV);
        let w = &mut *self.d;
        *w = [0.0; NV];
        for j in 0..n {
            let a = usize::from(act[j]);
            let (Some(g), Some(&ha)) = (self.rows.get(a), self.h.get(a)) else {
                return false;
            };
            let mut acc = dot(g, &self.x) - ha;
            for k in 0..j {
                if let Some(&rkj) = self.R.get((k, j)) {
                    acc -= rkj * w[k];
                }
            }
            let Some(&rjj) = self.R.get((j, j)) else {
                return false;
            };
            w[j] = acc / rjj;
        }
        *mult = [0.0; NV];
        back_substitute(self.R, w, n, mult);
        mult.iter().chain(w.iter()).all(|v| v.is_finite())
    }

    fn hot_move(&mut self, nact: usize) {
        for (col, &wj) in self.J.data.0.iter().zip(self.d.iter()).take(nact) {
            for (xk, c) in self.x.iter_mut().zip(col) {
                *xk += c * wj;
            }
        }
    }
}

/// `r[..nact] = R^-1 d[..nact]` by back substitution on the leading
/// `nact x nact` block of the upper-triangular `R` (`r` comes zeroed). The
/// same products and subtractions in the same order in both forms: for small
/// `NV` (the controller's 6) both loops run over the constant `NV` with the
/// test `< nact` inside, which the compiler unrolls fully; for larger `NV`
/// over `nact` (fully unrolled, the `NV^2 / 2` tests would cost more than
/// they save). Measured in `docs/solvers.md`.
#[inline(always)]
fn back_substitute<const NV: usize>(
    R: &SMatrix<f64, NV, NV>,
    d: &[f64; NV],
    nact: usize,
    r: &mut [f64; NV],
) {
    let nact = nact.min(NV);
    if NV <= 8 {
        for i in (0..NV).rev() {
            if i < nact {
                let mut acc = d[i];
                for k in (i + 1)..NV {
                    if k < nact {
                        acc -= R[(i, k)] * r[k];
                    }
                }
                r[i] = acc / R[(i, i)];
            }
        }
    } else {
        // Checked access: the optimiser does not see `nact <= NV` here on
        // every target (nopanic/); every access is in bounds.
        for i in (0..nact).rev() {
            let (Some(&di), Some(&rii)) = (d.get(i), R.get((i, i))) else {
                continue;
            };
            let mut acc = di;
            for k in (i + 1)..nact {
                if let (Some(&rik), Some(&rk)) = (R.get((i, k)), r.get(k)) {
                    acc -= rik * rk;
                }
            }
            if let Some(ri) = r.get_mut(i) {
                *ri = acc / rii;
            }
        }
    }
}

/// Adds a row whose `d = J' n` is given: one Householder reflection of
/// columns `nact..NV` of `J` maps `d[nact..]` to `alpha e_nact` (`|alpha| =
/// |d[nact..]|`), and `d[..nact], alpha` becomes column `nact` of `R`. Half
/// the flops of the equivalent Givens sweep, and all of them vectorise. False
/// when the active set is full (`nact == NV`) or the new diagonal of `R` is
/// zero or not finite.
fn householder_add<const NV: usize>(
    J: &mut SMatrix<f64, NV, NV>,
    R: &mut SMatrix<f64, NV, NV>,
    nact: usize,
    d: &[f64; NV],
) -> bool {
    if nact >= NV {
        return false;
    }
    let mut d = *d;
    let d0 = d[nact];
    let mut tail = 0.0; // |d[nact+1..]|^2
    for &dj in d.iter().skip(nact + 1) {
        tail += dj * dj;
    }
    if tail > 0.0 {
        // x = d[nact..], alpha = -sign(x_0) |x|, v = x - alpha e_0 (no
        // cancellation), reflection I - beta v v' with beta = 2 / v'v and
        // v'v = 2 |x| (|x| + |x_0|).
        let norm = crate::float::sqrt(d0 * d0 + tail);
        let alpha = if d0 >= 0.0 { -norm } else { norm };
        let mut v = d;
        v[nact] = d0 - alpha;
        let beta = 1.0 / (norm * (norm + d0.abs()));
        // J2 <- J2 (I - beta v v'): w = J2 v, then column j -= beta v_j w.
        let mut w = [0.0f64; NV];
        for (col, &vj) in J.data.0.iter().zip(&v).skip(nact) {
            for (wk, c) in w.iter_mut().zip(col) {
                *wk += c * vj;
            }
        }
        for (col, &vj) in J.data.0.iter_mut().zip(&v).skip(nact) {
            let f = beta * vj;
            for (c, wk) in col.iter_mut().zip(&w) {
                *c -= f * wk;
            }
        }
        d[nact] = alpha;
    }
    // Column `nact` of R gets d[..=nact] (checked access, as in givens_drop).
    let Some(col) = R.data.0.get_mut(nact) else {
        return false;
    };
    for (r, &di) in col.iter_mut().zip(&d).take(nact + 1) {
        *r = di;
    }
    col.get(nact).is_some_and(|&r| r != 0.0 && r.is_finite())
}

/// Removes active row `l` (of `nact`): deletes column `l` of `R` and
/// restores the triangle with Givens rotations, applied to `J` as well.
// Inlined (as the compiler chose when the loop was written out here, on
// x86-64 and on the Cortex-M7; out of line it costs the paper QPs 4 %).
#[inline(always)]
fn givens_drop<const NV: usize>(
    J: &mut SMatrix<f64, NV, NV>,
    R: &mut SMatrix<f64, NV, NV>,
    nact: usize,
    l: usize,
) {
    let nact = nact.min(NV); // invariant of the iteration, stated for the compiler
    for col in l..nact.saturating_sub(1) {
        for i in 0..NV {
            R[(i, col)] = R[(i, col + 1)];
        }
    }
    if nact >= 1 {
        for i in 0..NV {
            R[(i, nact - 1)] = 0.0;
        }
    }
    // Column `col` now has a sub-diagonal entry at row col+1 for col >= l.
    for col in l..nact.saturating_sub(1) {
        let (a, b) = (R[(col, col)], R[(col + 1, col)]);
        if b == 0.0 {
            continue;
        }
        let (c, s, rr) = givens(a, b);
        R[(col, col)] = rr;
        R[(col + 1, col)] = 0.0;
        // Columns k in col+1..nact-1 (checked access: the optimiser cannot
        // prove the bounds for every NV, see nopanic/).
        for rk in R.data.0.iter_mut().take(nact - 1).skip(col + 1) {
            if let [.., ra, rb] = rk.get_mut(..col + 2).unwrap_or(&mut []) {
                let (a, b) = (*ra, *rb);
                *ra = c * a + s * b;
                *rb = -s * a + c * b;
            }
        }
        rotate_columns(J, col, c, s);
    }
}

/// `[Ji, Jj] <- [c Ji + s Jj, -s Ji + c Jj]` for the adjacent columns `i` and
/// `j = i + 1` (the callers' only use); with `j >= NV` nothing happens.
fn rotate_columns<const NV: usize>(J: &mut SMatrix<f64, NV, NV>, i: usize, c: f64, s: f64) {
    // Column-major storage: `J.data.0[k]` is column `k`.
    if let Some([ji, jj]) = J.data.0.get_mut(i..i.saturating_add(2)) {
        for k in 0..NV {
            let (a, b) = (ji[k], jj[k]);
            ji[k] = c * a + s * b;
            jj[k] = -s * a + c * b;
        }
    }
}
