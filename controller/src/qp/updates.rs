//! The updates of the orthogonal factor `J`, `R` of the active set (the
//! bottom of the solver; the factor itself is `qp/orthogonal.rs`): a row
//! added by one Householder reflection ([`householder_add`]), a row dropped
//! by Givens rotations ([`givens_drop`]), and the back substitution on `R`
//! by rows ([`back_substitute`]) or by columns
//! ([`back_substitute_by_columns`]).

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector};

use crate::linalg::{column, column_mut, columns_in, columns_in_mut, givens};

/// `r[..nact] = R^-1 d[..nact]` by back substitution on the leading
/// `nact x nact` block of the upper-triangular `R` (`r` comes zeroed). The
/// same products and subtractions in the same order in both forms: for small
/// `NV` (the controller's 6) both loops run over the constant `NV` with the
/// test `< nact` inside, which the compiler unrolls fully; for larger `NV`
/// (and run-time sizes) over `nact` (fully unrolled, the `NV^2 / 2` tests
/// would cost more than they save). Measured in `docs/solvers.md`.
/// Inlined on hosts; one out-of-line copy on bare-metal targets, shared
/// with the resumed solves (`qp/resolve.rs`), for flash.
#[cfg_attr(not(target_os = "none"), inline(always))]
#[cfg_attr(target_os = "none", inline(never))]
pub(super) fn back_substitute<NV: Dim>(
    R: &OMatrix<f64, NV, NV>,
    d: &[f64],
    nact: usize,
    r: &mut [f64],
) where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    let small = NV::try_to_usize().is_some_and(|n| n <= 8);
    let nv = R.nrows();
    let (Some(d), Some(r)) = (d.get(..nv), r.get_mut(..nv)) else {
        return;
    };
    let nact = nact.min(nv);
    if small {
        for i in (0..nv).rev() {
            if i < nact {
                let mut acc = d[i];
                for k in (i + 1)..nv {
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
pub(super) fn householder_add<NV: Dim, const SPARSE: bool>(
    J: &mut OMatrix<f64, NV, NV>,
    R: &mut OMatrix<f64, NV, NV>,
    nact: usize,
    d: &[f64],
) -> bool
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV> + nalgebra::allocator::Allocator<NV>,
{
    let (nvd, _) = J.shape_generic();
    let n = nvd.value();
    if nact >= n {
        return false;
    }
    let mut v = OVector::<f64, NV>::zeros_generic(nvd, nalgebra::U1);
    for (a, &b) in v.as_mut_slice().iter_mut().zip(d) {
        *a = b;
    }
    let d0 = v.get(nact).copied().unwrap_or(0.0);
    let mut tail = 0.0; // |d[nact+1..]|^2
    for &dj in v.as_slice().iter().skip(nact + 1) {
        tail += dj * dj;
    }
    let mut diag = d0;
    if tail > 0.0 {
        // x = d[nact..], alpha = -sign(x_0) |x|, v = x - alpha e_0 (no
        // cancellation), reflection I - beta v v' with beta = 2 / v'v and
        // v'v = 2 |x| (|x| + |x_0|).
        let norm = crate::linalg::sqrt(d0 * d0 + tail);
        let alpha = if d0 >= 0.0 { -norm } else { norm };
        if let Some(vn) = v.get_mut(nact) {
            *vn = d0 - alpha;
        }
        let beta = 1.0 / (norm * (norm + d0.abs()));
        // J2 <- J2 (I - beta v v'): w = J2 v, then column j -= beta v_j w.
        let mut w = OVector::<f64, NV>::zeros_generic(nvd, nalgebra::U1);
        let v2 = v.as_slice().get(nact..).unwrap_or(&[]);
        for (col, &vj) in columns_in(J.as_slice(), n, nact, n).zip(v2) {
            if SPARSE && vj == 0.0 {
                continue;
            }
            for (wk, c) in w.as_mut_slice().iter_mut().zip(col) {
                *wk += c * vj;
            }
        }
        for (col, &vj) in columns_in_mut(J.as_mut_slice(), n, nact, n).zip(v2) {
            if SPARSE && vj == 0.0 {
                continue;
            }
            let f = beta * vj;
            for (c, wk) in col.iter_mut().zip(w.as_slice().iter()) {
                *c -= f * wk;
            }
        }
        diag = alpha;
    }
    // Column `nact` of R gets d[..nact], then the new diagonal (checked
    // access, as in givens_drop).
    let Some(col) = column_mut(R.as_mut_slice(), n, nact) else {
        return false;
    };
    for (r, &di) in col.iter_mut().zip(d).take(nact) {
        *r = di;
    }
    let Some(rd) = col.get_mut(nact) else {
        return false;
    };
    *rd = diag;
    diag != 0.0 && diag.is_finite()
}

/// Removes active row `l` (of `nact`): deletes column `l` of `R` and
/// restores the triangle with Givens rotations, applied to `J` as well.
// Inlined on hosts (as the compiler chose when the loop was written out
// here; out of line it costs the paper QPs 4 %); one out-of-line copy on
// bare-metal targets, shared by the iteration's drops and the resumed
// solves' (`qp/resolve.rs`), for flash.
#[cfg_attr(not(target_os = "none"), inline(always))]
#[cfg_attr(target_os = "none", inline(never))]
pub(super) fn givens_drop<NV: Dim>(
    J: &mut OMatrix<f64, NV, NV>,
    R: &mut OMatrix<f64, NV, NV>,
    nact: usize,
    l: usize,
) where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    let nv = R.nrows();
    let nact = nact.min(nv); // invariant of the iteration, stated for the compiler
    for col in l..nact.saturating_sub(1) {
        if let Some(pair) = col
            .checked_mul(nv)
            .and_then(|a| R.as_mut_slice().get_mut(a..a.saturating_add(2 * nv)))
        {
            let (dst, src) = pair.split_at_mut(nv.min(pair.len()));
            crate::linalg::copy(dst, src);
        }
    }
    if let Some(last) = nact
        .checked_sub(1)
        .and_then(|c| column_mut(R.as_mut_slice(), nv, c))
    {
        last.fill(0.0);
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
        for rk in columns_in_mut(R.as_mut_slice(), nv, col + 1, nact - 1) {
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
fn rotate_columns<NV: Dim>(J: &mut OMatrix<f64, NV, NV>, i: usize, c: f64, s: f64)
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    let n = J.nrows();
    // Column-major storage: columns i and i + 1 are contiguous.
    let Some(start) = i.checked_mul(n) else {
        return;
    };
    let Some(pair) = J.as_mut_slice().get_mut(start..start.saturating_add(2 * n)) else {
        return;
    };
    let (ji, jj) = pair.split_at_mut(n.min(pair.len()));
    for (a, b) in ji.iter_mut().zip(jj.iter_mut()) {
        let (x, y) = (*a, *b);
        *a = c * x + s * y;
        *b = -s * x + c * y;
    }
}

/// `r[..nact] = R^-1 d[..nact]` for the upper-triangular leading
/// `nact x nact` block of `R`, by columns, in place in `r` (`r = d`, then
/// from the last row up `r_i /= R_ii` and `r[..i] -= r_i R[..i, i]`: a
/// contiguous column, independent lanes). The products of
/// `orthogonal::back_substitute` in another order (other rounding), without
/// its chain of dependent subtractions per row.
pub(super) fn back_substitute_by_columns<NV: Dim>(
    R: &OMatrix<f64, NV, NV>,
    d: &[f64],
    nact: usize,
    r: &mut [f64],
) where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    let n = R.nrows();
    let nact = nact.min(n);
    crate::linalg::copy(r, d.get(..nact).unwrap_or(&[]));
    for i in (0..nact).rev() {
        let (Some(col), Some((ri_slot, above))) = (
            column(R.as_slice(), n, i),
            r.get_mut(..=i).and_then(|h| h.split_last_mut()),
        ) else {
            continue;
        };
        let Some(&rii) = col.get(i) else {
            continue;
        };
        let ri = *ri_slot / rii;
        *ri_slot = ri;
        for (wk, &rk) in above.iter_mut().zip(col) {
            *wk -= ri * rk;
        }
    }
}
