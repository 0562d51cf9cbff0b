//! The active set of the least-distance path ([`super::LdpSolverOf::solve`]):
//! the Cholesky factor of the Gram matrix of the active scaled rows and its
//! inverse, with the slacks of all rows standing for the iterate.

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, U1};

use super::{LdpSolverOf, PIVOT_FALLBACK, slack_holds};
use crate::active_set::{ActiveSetFactor, AddError};
use crate::linalg::{column, column_mut, columns, dot_d, givens};
use crate::qp::QpAllocator;

/// `z -= M_A' r` over the first `nact` active rows (scaled rows `mhat`,
/// column-major with `n` rows).
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

/// The active set of [`LdpSolverOf::solve`]: the Cholesky factor `C` of
/// `M_A M_A'` (scaled rows) and its inverse, with the scaled slacks of all
/// rows standing for the primal iterate `u`. The iteration itself is
/// [`crate::active_set::iterate`].
pub(super) struct Gram<'a, NV: Dim, NC: Dim>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The prepared rows, their Gram matrix and thresholds.
    pub(super) ldp: &'a LdpSolverOf<NV, NC>,
    /// Number of variables (a constant for the static sizes).
    pub(super) n: usize,
    /// Scaled slacks `(d_i - m_i u) / |m_i|` of all rows.
    pub(super) s: OVector<f64, NC>,
    /// Cholesky factor of `M_A M_A'`, row `i` stored as column `i`, zeros
    /// above the diagonal kept exactly zero (the solves use full-length
    /// dots). The factors are the caller's locals: their addresses go to
    /// [`chol_drop`], and an escaping field would keep every other field of
    /// this struct in memory.
    pub(super) C: &'a mut OMatrix<f64, NV, NV>,
    /// `C^-1`, lower triangular, stored as `C`.
    pub(super) Ci: &'a mut OMatrix<f64, NV, NV>,
    /// `tol_dependence^2`.
    pub(super) tol_dep2: f64,
    /// `w = C^-1 M_A m_p` of the last direction: the new row of `C`.
    pub(super) w: OVector<f64, NV>,
    /// Scratch: the right-hand side of the solves.
    pub(super) b: OVector<f64, NV>,
    /// Scratch for run-time sizes: the component of the new row outside
    /// the active span (a local of `direction` for the static sizes).
    pub(super) z: OVector<f64, NV>,
    /// Scratch: the second projection's `w` and `r`.
    pub(super) w2: OVector<f64, NV>,
    /// Scratch, see `w2`; also the multipliers of the last
    /// [`ActiveSetFactor::hot_multipliers`].
    pub(super) r2: OVector<f64, NV>,
    /// The scaled slacks at `u = 0`, `d_i / |m_i|` (for the equality rows:
    /// their minimiser does not depend on the iterate).
    pub(super) s0: &'a OVector<f64, NC>,
    /// `|z|^2`, `z = m_p - M_A' r` the component of the last row outside the
    /// active span.
    pub(super) z2: f64,
    /// The last row was linearly dependent on the active rows.
    pub(super) dependent: bool,
}

impl<NV: Dim, NC: Dim> Gram<'_, NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// The number of variables: the constant for the static sizes (the
    /// stored field is not seen as one, and the column access would divide
    /// by it).
    #[inline(always)]
    fn n(&self) -> usize {
        NV::try_to_usize().unwrap_or(self.n)
    }
}

impl<NV: Dim, NC: Dim> ActiveSetFactor for Gram<'_, NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    #[inline(always)]
    fn violation(&mut self, i: usize, blocked: bool) -> Option<f64> {
        // Most rows hold with a positive slack: that test first, on a plain
        // load (the scan runs `m` times per add; an `Option` per access
        // costs it three times the instructions).
        let (s, thr) = (self.s.as_slice(), self.ldp.thr.as_slice());
        if i >= s.len() || i >= thr.len() {
            return None;
        }
        let si = s[i];
        if si >= 0.0 || blocked || slack_holds(si, thr[i]) {
            return None;
        }
        Some(if si.is_finite() { si } else { f64::NAN })
    }

    #[inline(always)]
    fn direction(&mut self, p: usize, act: &[u16], nact: usize, r: &mut [f64]) -> Option<f64> {
        let ldp = self.ldp;
        let n = self.n();
        let mhat = ldp.mhat.as_slice();
        let nc = ldp.K.nrows();
        let (Some(mp), Some(kp), Some(&sp)) = (
            column(mhat, n, p),
            column(ldp.K.as_slice(), nc, p),
            self.s.get(p),
        ) else {
            return None;
        };
        // w = C^-1 M_A m_p, r = C^-T w = (M_A M_A')^-1 M_A m_p (entries
        // `..nact` of `b` and `w`; `add` copies `w[..nact]` into `C`).
        for (bi, &a) in self.b.as_mut_slice().iter_mut().zip(act).take(nact) {
            *bi = kp.get(usize::from(a)).copied().unwrap_or(0.0);
        }
        chol_solve(self.Ci, self.b.as_slice(), nact, self.w.as_mut_slice(), r);
        // z = m_p - M_A' r: the component of m_p outside the active span.
        // For the static sizes a local (kept in registers; as a field it was
        // stored after every active row), for run-time sizes the field (no
        // allocation per direction).
        let mut local;
        let z: &mut [f64] = if NV::try_to_usize().is_some() {
            local = OVector::<f64, NV>::zeros_generic(self.w.shape_generic().0, U1);
            local.as_mut_slice()
        } else {
            self.z.as_mut_slice()
        };
        crate::linalg::copy(z, mp);
        sub_active(mhat, n, z, act, r, nact);
        let mut z2 = dot_d::<NV>(z, z);
        if z2 < REFINE2 {
            // Cancellation: z carries rounding of order eps cond(M_A)^2.
            // Project it once more (Gram-Schmidt "twice is enough"),
            // r2 = (M_A M_A')^-1 M_A z, z -= M_A' r2, r += r2.
            for (bi, &a) in self.b.as_mut_slice().iter_mut().zip(act).take(nact) {
                if let Some(ma) = column(mhat, n, usize::from(a)) {
                    *bi = dot_d::<NV>(ma, z);
                }
            }
            self.r2.as_mut_slice().fill(0.0);
            chol_solve(
                self.Ci,
                self.b.as_slice(),
                nact,
                self.w2.as_mut_slice(),
                self.r2.as_mut_slice(),
            );
            sub_active(mhat, n, z, act, self.r2.as_slice(), nact);
            for (ri, r2i) in r.iter_mut().zip(self.r2.as_slice().iter()).take(nact) {
                *ri += r2i;
            }
            for (wi, w2i) in self
                .w
                .as_mut_slice()
                .iter_mut()
                .zip(self.w2.as_slice().iter())
                .take(nact)
            {
                *wi += w2i;
            }
            z2 = dot_d::<NV>(z, z);
        }
        // Full (primal) step length t2 (|mhat_p| = 1).
        // With NV rows active (independent) the span is everything.
        let dependent = z2 <= self.tol_dep2 || nact >= n;
        let t2 = if dependent { f64::INFINITY } else { -sp / z2 };
        self.z2 = z2;
        self.dependent = dependent;
        Some(t2)
    }

    #[inline(always)]
    fn advance(&mut self, p: usize, t: f64, r: &[f64], act: &[u16], nact: usize) {
        let K = self.ldp.K.as_slice();
        let nc = self.ldp.K.nrows();
        let m = self.ldp.m.min(nc);
        let (false, Some(kp)) = (self.dependent, column(K, nc, p)) else {
            return;
        };
        // Slices of the row count (not `take(m)` on longer ones): the loops
        // then vectorise.
        let Some(s) = self.s.as_mut_slice().get_mut(..m) else {
            return;
        };
        // u moves by -t z: slack_i grows by t mhat_i . z
        // = t (K_ip - sum_j r_j K_i,A_j).
        for (si, &k) in s.iter_mut().zip(kp) {
            *si += t * k;
        }
        for (&a, &rj) in act.iter().zip(r).take(nact) {
            if let Some(ka) = column(K, nc, usize::from(a)) {
                let f = t * rj;
                for (si, &k) in s.iter_mut().zip(ka) {
                    *si -= f * k;
                }
            }
        }
    }

    /// Appends the row `[w', |z|]` to `C` and `[-r', 1] / |z|` to `C^-1`;
    /// asks for a restart when `|z| <` [`PIVOT_FALLBACK`].
    #[inline(always)]
    fn add(&mut self, p: usize, r: &[f64], nact: usize) -> Result<(), AddError> {
        let n = self.n();
        if NV::try_to_usize().is_none() {
            grow(self.C, n, nact);
            grow(self.Ci, n, nact);
        }
        let diag = libm::sqrt(self.z2);
        let Some(row) = column_mut(self.C.as_mut_slice(), n, nact) else {
            return Err(AddError::Numerical);
        };
        if !(diag > 0.0 && diag.is_finite()) {
            return Err(AddError::Numerical);
        }
        if diag < PIVOT_FALLBACK {
            return Err(AddError::Restart);
        }
        // Entries `nact + 1..` of the row are zero already (rows past the
        // active ones are zero: zeroed at the start and by `chol_drop`).
        crate::linalg::copy(row, self.w.as_slice().get(..nact).unwrap_or(&[]));
        if let Some(c) = row.get_mut(nact) {
            *c = diag;
        }
        // C^-1 gains the row [-(C^-T w)' / |z|, 1 / |z|] = [-r', 1] / |z|.
        if let Some(ci) = column_mut(self.Ci.as_mut_slice(), n, nact) {
            let inv = 1.0 / diag;
            for (c, rk) in ci.iter_mut().zip(r).take(nact) {
                *c = -rk * inv;
            }
            if let Some(c) = ci.get_mut(nact) {
                *c = inv;
            }
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

    fn equalities_capable(&self) -> bool {
        self.ldp.solver.equalities_capable()
    }

    fn slack(&self, i: usize) -> (f64, f64) {
        match (self.s.get(i), self.ldp.thr.get(i)) {
            (Some(&si), Some(&thr)) => (si, thr),
            _ => (f64::NAN, 0.0),
        }
    }

    /// [`ActiveSetFactor::direction`] for the new row (its `w` and `|z|`),
    /// then the add of the factor without a step (the slacks stay).
    fn hot_add(&mut self, p: usize, act: &[u16], nact: usize) -> Result<bool, AddError> {
        // (`direction` uses the scratch vectors itself.)
        let mut r = OVector::<f64, NV>::zeros_generic(self.w.shape_generic().0, U1);
        let dir = self.direction(p, act, nact, r.as_mut_slice());
        match dir {
            None => Err(AddError::Numerical),
            Some(_) if self.dependent => Ok(false),
            Some(_) => {
                let sp = self.s.get(p).copied();
                let added = self.add(p, r.as_slice(), nact);
                // `add` zeroes the slack of `p` (a full step); no step here.
                if let (Some(s), Some(v)) = (self.s.get_mut(p), sp) {
                    *s = v;
                }
                added.map(|()| true)
            }
        }
    }

    /// The minimiser of `1/2 |u|^2` on the active rows held as equalities,
    /// `u = M_A' (M_A M_A')^-1 d_A` (scaled rows; it does not depend on the
    /// iterate), has the multipliers `-(M_A M_A')^-1 d_A`.
    fn hot_multipliers(&mut self, act: &[u16], nact: usize, mult: &mut [f64]) -> bool {
        let n = nact.min(self.n());
        for (bi, &a) in self.b.as_mut_slice().iter_mut().zip(act).take(n) {
            *bi = self.s0.get(usize::from(a)).copied().unwrap_or(f64::NAN);
        }
        self.r2.as_mut_slice().fill(0.0);
        chol_solve(
            self.Ci,
            self.b.as_slice(),
            n,
            self.w2.as_mut_slice(),
            self.r2.as_mut_slice(),
        );
        mult.fill(0.0);
        for (m, &r) in mult.iter_mut().zip(self.r2.as_slice()).take(n) {
            *m = -r;
        }
        mult.iter().all(|v| v.is_finite())
    }

    /// The slacks at that minimiser: `s_i = s0_i + sum_j lambda_j K_{i,a_j}`
    /// (`0` on the active rows).
    fn hot_move(&mut self, act: &[u16], nact: usize) {
        let K = self.ldp.K.as_slice();
        let nc = self.ldp.K.nrows();
        let m = self.ldp.m.min(nc);
        let s = self.s.as_mut_slice();
        for (si, &s0) in s.iter_mut().zip(self.s0.as_slice()).take(m) {
            *si = s0;
        }
        for (&a, &r) in act.iter().zip(self.r2.as_slice()).take(nact) {
            if let Some(ka) = column(K, nc, usize::from(a)) {
                // lambda_j = -r_j
                for (si, &k) in s.iter_mut().zip(ka).take(m) {
                    *si -= r * k;
                }
            }
        }
        for &a in act.iter().take(nact) {
            if let Some(sa) = s.get_mut(usize::from(a)) {
                *sa = 0.0;
            }
        }
    }
}

/// Rows of the factors `C`, `C^-1` allocated at the start of a solve with
/// run-time sizes (at most `n`); [`grow`] doubles them when needed.
pub(super) const FIRST_ROWS: usize = 8;

/// Makes row `j` (column `j` of the storage) of a factor with `n` rows of
/// length `n` exist, doubling the rows allocated (at most `n`; the rows
/// added are zero). Run-time sizes only: the static factors have all `n`.
fn grow<NV: Dim>(M: &mut OMatrix<f64, NV, NV>, n: usize, j: usize)
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    let (nv, cols) = M.shape_generic();
    let cols = cols.value();
    if j < cols || j >= n {
        return;
    }
    let k = cols.saturating_mul(2).max(j + 1).min(n);
    let mut bigger = OMatrix::<f64, NV, NV>::zeros_generic(nv, NV::from_usize(k));
    crate::linalg::copy(bigger.as_mut_slice(), M.as_slice());
    *M = bigger;
}

/// Below this squared norm of the new row's component outside the active span
/// (the rows have unit norm: `|z| < 0.1`), the component is projected a second
/// time.
const REFINE2: f64 = 1e-2;

/// `w = C^-1 b` and `r = C^-T w = (C C')^-1 b` on the leading `nact x nact`
/// block, from the inverse factor `Ci = C^-1` (lower triangular, zeros above
/// the diagonal, row `i` stored as column `i`): two matrix-vector products,
/// no chain of dependent divisions or dot products as in substitution. Only
/// `b[..nact]` is read; entries `..nact` of `w` are written and of `r`
/// accumulated into, which must come zeroed there; the rest are left as they
/// are. Row `i` of `Ci` is read over its non-zero entries `..=i` alone: the
/// products skipped are exact zeros (the rows of `C^-1` finite), which leave
/// the sums as they are (they start at +0 and never become -0), so the bits
/// are those of full-length products.
#[inline(always)]
fn chol_solve<NV: Dim>(
    Ci: &OMatrix<f64, NV, NV>,
    b: &[f64],
    nact: usize,
    w: &mut [f64],
    r: &mut [f64],
) where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV> + nalgebra::allocator::Allocator<NV>,
{
    let n = Ci.nrows();
    let (Some(b), Some(r)) = (b.get(..nact), r.get_mut(..nact)) else {
        return;
    };
    for (i, (wi, row)) in w
        .iter_mut()
        .zip(columns(Ci.as_slice(), n))
        .take(nact)
        .enumerate()
    {
        // Equal lengths: `dot_d` pairs the entries of each.
        if let (Some(row), Some(b)) = (row.get(..=i), b.get(..=i)) {
            *wi = dot_d::<NV>(row, b);
        }
    }
    for (i, (&wi, row)) in w
        .iter()
        .zip(columns(Ci.as_slice(), n))
        .take(nact)
        .enumerate()
    {
        let row = row.get(..=i).unwrap_or(row);
        for (rk, c) in r.iter_mut().zip(row) {
            *rk += wi * c;
        }
    }
}

/// Removes row `l` (of `nact`) from the Cholesky factor `C` of `M_A M_A'`
/// (row `i` stored as column `i`): the rows below move up, and Givens
/// rotations of column pairs restore the triangle (`C C'` stays the Gram
/// matrix of the remaining rows). The rows `l..` of the inverse factor `Ci`
/// are then recomputed from `C Ci = I`.
pub(super) fn chol_drop<NV: Dim>(
    C: &mut OMatrix<f64, NV, NV>,
    Ci: &mut OMatrix<f64, NV, NV>,
    nact: usize,
    l: usize,
) where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV> + nalgebra::allocator::Allocator<NV>,
{
    let (nvd, _) = C.shape_generic();
    let n = nvd.value();
    let nact = nact.min(n);
    if l >= nact {
        return;
    }
    let last = nact - 1;
    // `C[(k, i)]` is entry (i, k) of the factor (row i stored as column i).
    // Checked access (the optimiser does not prove `i + 1 < NV` on every
    // target, see nopanic/); always in bounds.
    for i in l..last {
        if let Some(pair) = i
            .checked_mul(n)
            .and_then(|a| C.as_mut_slice().get_mut(a..a.saturating_add(2 * n)))
        {
            let (row, next) = pair.split_at_mut(n.min(pair.len()));
            crate::linalg::copy(row, next);
        }
    }
    if let Some(row) = column_mut(C.as_mut_slice(), n, last) {
        row.fill(0.0);
    }
    if let Some(row) = column_mut(Ci.as_mut_slice(), n, last) {
        row.fill(0.0);
    }
    // Rows k..last-1 now reach column k+1; rotate columns k, k+1.
    for k in l..last {
        let (Some(&a), Some(&b)) = (C.get((k, k)), C.get((k + 1, k))) else {
            continue;
        };
        if b == 0.0 {
            continue;
        }
        let (c, s, r) = givens(a, b);
        if let Some(v) = C.get_mut((k, k)) {
            *v = r;
        }
        if let Some(v) = C.get_mut((k + 1, k)) {
            *v = 0.0;
        }
        for row in crate::linalg::columns_in_mut(C.as_mut_slice(), n, k + 1, last) {
            if let Some([ra, rb]) = row.get_mut(k..k + 2) {
                let (a, b) = (*ra, *rb);
                *ra = c * a + s * b;
                *rb = -s * a + c * b;
            }
        }
    }
    // Row i of C Ci = I: C_ii Ci_i = e_i - sum_{k<i} C_ik Ci_k.
    let mut row = OVector::<f64, NV>::zeros_generic(nvd, U1);
    for i in l..last {
        row.fill(0.0);
        if let Some(v) = row.get_mut(i) {
            *v = 1.0;
        }
        for k in 0..i {
            let f = C.get((k, i)).copied().unwrap_or(0.0);
            if let Some(cik) = column(Ci.as_slice(), n, k) {
                for (a, b) in row.iter_mut().zip(cik) {
                    *a -= f * b;
                }
            }
        }
        let inv = 1.0 / C.get((i, i)).copied().unwrap_or(0.0);
        for a in row.iter_mut() {
            *a *= inv;
        }
        if let Some(dst) = column_mut(Ci.as_mut_slice(), n, i) {
            crate::linalg::copy(dst, row.as_slice());
        }
    }
}
