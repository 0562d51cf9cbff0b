//! The Cholesky factor of the hot start's Gram matrix (the guess,
//! `qp/guess.rs`): `K = M M'` for the marked
//! rows `m_j = L^-1 g_j` (the columns of `M`), `K = C C'` with `C` lower
//! triangular, formed over the rows' spans.
//!
//! The controller's rows have short or one-sided spans (a velocity or
//! reachability row of step `k` touches the variables `0..2k + 2`, an
//! obstacle row `2k - 2..2k + 2`), so most entries of `K` are
//! dot products over a part of the rows, and many are zero. Every product
//! left out is an exact zero (`0 * x` for a finite `x`) that would leave its
//! sum as it is (a sum that starts at +0 never becomes -0), so the factor
//! has the bits of the one formed over all entries:
//!
//! * `K_ij` is the [`dot`] over the intersection of the two spans (whose
//!   start is even: each product keeps its partial sum), +0 when they do not
//!   meet.
//! * Row `i` of `C` is zero before `f_i`, the first row whose span meets row
//!   `i`'s (the entries of `K` before it are zero, and by induction so are
//!   those of `C`): the entries before `f_i` are not formed, and the sums of
//!   products of two rows start at `max(f_i, f_j)`.
//!
//! The unit tests below compare the factor with the one formed entry by
//! entry over all entries, bit for bit.
//!
//! The guess's matrices `M` and `T` are a workspace ([`GuessWork`]) kept
//! between solves (the controller's, cycle to cycle, in its probe state) and
//! not cleared: the guess writes every entry it reads (the columns `0..k`
//! of `M`; of column `i` of `T` the entries `0..=i`, those before `f_i` as
//! zeros), so its results do not depend on what the workspace held.

use nalgebra::{ArrayStorage, Const, SMatrix};
use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector, U1};

use super::spans::{Span, unpack};
use crate::linalg::{column, columns, dot};

/// The number of variables from which [`factor_gram`] works over the spans
/// (measured in `docs/solvers.md`: at 20 variables the spans cost more than
/// they save, at 40 they save a fifth of the controller's `step`).
const SPANS_FROM: usize = 32;

/// The matrices of the hot start's guess (module docs), `NV x NV`
/// column-major, entries dimensionless scratch.
#[derive(Clone, Debug)]
pub(super) struct GuessWork<NV: Dim>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    /// `M`: column `j` is `m_j = L^-1 g_j` of the `j`-th marked row.
    pub M: OMatrix<f64, NV, NV>,
    /// `T = C'` (the Cholesky factor of `M M'`, transposed).
    pub T: OMatrix<f64, NV, NV>,
}

impl<NV: Dim> GuessWork<NV>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    /// Zeroed storage for `nv` variables (hosts: bare-metal probe states
    /// hold none).
    #[cfg_attr(target_os = "none", allow(dead_code))]
    pub(super) fn zeros(nv: NV) -> Self {
        GuessWork {
            M: OMatrix::zeros_generic(nv, nv),
            T: OMatrix::zeros_generic(nv, nv),
        }
    }
}

impl<const NV: usize> GuessWork<Const<NV>> {
    /// Zeroed storage, for `const` initialisers (hosts, as
    /// [`GuessWork::zeros`]).
    #[cfg_attr(target_os = "none", allow(dead_code))]
    pub(super) const EMPTY: Self = GuessWork {
        M: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
        T: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
    };
}

/// Factors `K = M M'` of the first `k` columns of `M` (`NV x NV`,
/// column-major) into `T = C'` (column `i` of `T` is row `i` of `C`; of
/// column `i` the entries `0..=i` are written, whatever `T` held: the
/// others are never read). False when an entry of `M` is not finite or a pivot is
/// below `1e-10` of its diagonal entry (nearly dependent rows).
pub(super) fn factor_gram<NV: Dim>(
    M: &OMatrix<f64, NV, NV>,
    k: usize,
    T: &mut OMatrix<f64, NV, NV>,
) -> bool
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV> + nalgebra::allocator::Allocator<NV>,
{
    let (nv, _) = M.shape_generic();
    let n = nv.value();
    let k = k.min(n);
    let ms = M.as_slice();
    // Over the spans from `SPANS_FROM` variables on (and for run-time
    // sizes); below, the constant-length products over all entries (whose
    // full unrolling the spans' bookkeeping does not repay) and `f_i = 0`.
    let spans = NV::try_to_usize().is_none_or(|n| n >= SPANS_FROM);
    // The spans `lo..hi` of the columns (`lo` even; `0..0` for a zero
    // column), and `f_i`.
    let mut span = OVector::<Span, NV>::zeros_generic(nv, U1);
    let mut first = OVector::<Span, NV>::zeros_generic(nv, U1);
    for (i, m) in columns(ms, n).enumerate().take(if spans { k } else { 0 }) {
        if !m.iter().all(|v| v.is_finite()) {
            return false;
        }
        let lo = m.iter().position(|&v| v != 0.0);
        let hi = m.iter().rposition(|&v| v != 0.0);
        let (lo, hi) = match (lo, hi) {
            (Some(lo), Some(hi)) => (lo & !1, hi + 1),
            _ => (0, 0),
        };
        if let Some(s) = span.get_mut(i) {
            *s = (lo as Span) | ((hi as Span) << 16);
        }
        let f = span
            .as_slice()
            .iter()
            .take(i + 1)
            .position(|&s| {
                let (l, h) = unpack(s);
                l.max(lo) < h.min(hi)
            })
            .unwrap_or(i);
        if let Some(fi) = first.get_mut(i) {
            *fi = f as Span;
        }
    }
    let sp = |i: usize| {
        if spans {
            unpack(span.get(i).copied().unwrap_or(0))
        } else {
            (0, n)
        }
    };
    let fst = |i: usize| {
        if spans {
            first.get(i).copied().unwrap_or(0) as usize
        } else {
            0
        }
    };
    // `K_ij` over the spans' intersection.
    let gram = |mi: &[f64], i: usize, mj: &[f64], j: usize| {
        let ((li, hi), (lj, hj)) = (sp(i), sp(j));
        let (a, b) = (li.max(lj), hi.min(hj));
        match (mi.get(a..b), mj.get(a..b)) {
            (Some(x), Some(y)) if a < b => dot(x, y),
            _ => 0.0,
        }
    };
    for i in 0..k {
        let Some(mi) = column(ms, n, i) else {
            return false;
        };
        let fi = fst(i);
        let ts = T.as_mut_slice();
        let (done, rest) = ts.split_at_mut(i.saturating_mul(n).min(ts.len()));
        let Some(ti) = rest.get_mut(..n) else {
            return false;
        };
        // Row `i` of `C` before `f_i`: zeros (read by the products of the
        // rows after it and by the guess's back substitution).
        for t in ti.get_mut(..fi).unwrap_or(&mut []) {
            *t = 0.0;
        }
        // With the spans two entries at a time: their sums are independent
        // chains up to the last product of the second, which needs the first
        // (a sum started before its row's `max(f_i, f_j)` only takes exact
        // zeros more). Below `SPANS_FROM`, one at a time (fewer instructions
        // for the fully unrolled short rows, the same time).
        let mut j = fi;
        while j < i {
            let (Some(tj), Some(mj)) = (column(done, n, j), column(ms, n, j)) else {
                return false;
            };
            let mut s = gram(mi, i, mj, j);
            let pair = match (column(done, n, j + 1), column(ms, n, j + 1)) {
                (Some(t1), Some(m1)) if spans && j + 1 < i => Some((t1, gram(mi, i, m1, j + 1))),
                _ => None,
            };
            let l0 = fi.max(fst(j));
            match pair {
                Some((t1, mut s1)) => {
                    let l0 = l0.min(fi.max(fst(j + 1)));
                    if let (Some(a), Some(b), Some(b1)) =
                        (ti.get(l0..j), tj.get(l0..j), t1.get(l0..j))
                    {
                        for ((x, y), y1) in a.iter().zip(b).zip(b1) {
                            s -= x * y;
                            s1 -= x * y1;
                        }
                    }
                    let (Some(&cjj), Some(&c1j), Some(&c11)) =
                        (tj.get(j), t1.get(j), t1.get(j + 1))
                    else {
                        return false;
                    };
                    let cij = s / cjj;
                    s1 -= cij * c1j;
                    if let Some([e0, e1]) = ti.get_mut(j..j + 2) {
                        *e0 = cij;
                        *e1 = s1 / c11;
                    }
                    j += 2;
                }
                None => {
                    if let (Some(a), Some(b)) = (ti.get(l0..j), tj.get(l0..j)) {
                        for (x, y) in a.iter().zip(b) {
                            s -= x * y;
                        }
                    }
                    let (Some(&cjj), Some(cij)) = (tj.get(j), ti.get_mut(j)) else {
                        return false;
                    };
                    *cij = s / cjj;
                    j += 1;
                }
            }
        }
        let sii = gram(mi, i, mi, i);
        let mut s = sii;
        for &x in ti.get(fi..i).unwrap_or(&[]) {
            s -= x * x;
        }
        if s.is_nan() || s <= 1e-10 * sii {
            return false;
        }
        if let Some(cii) = ti.get_mut(i) {
            *cii = crate::linalg::sqrt(s);
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use nalgebra::SMatrix;

    use super::factor_gram;

    /// The Cholesky factor of `M M'` entry by entry over all `n` entries
    /// (the reference the spans must reproduce bit for bit).
    fn reference<const N: usize>(M: &SMatrix<f64, N, N>, k: usize) -> Option<SMatrix<f64, N, N>> {
        let mut C = SMatrix::<f64, N, N>::zeros();
        for i in 0..k {
            for j in 0..=i {
                let mut s = crate::linalg::dot(M.column(i).as_slice(), M.column(j).as_slice());
                for l in 0..j {
                    s -= C[(i, l)] * C[(j, l)];
                }
                if i == j {
                    let d = crate::linalg::dot(M.column(i).as_slice(), M.column(i).as_slice());
                    if s.is_nan() || s <= 1e-10 * d {
                        return None;
                    }
                    C[(i, i)] = crate::linalg::sqrt(s);
                } else {
                    C[(i, j)] = s / C[(j, j)];
                }
            }
        }
        Some(C.transpose())
    }

    /// Rows shaped as the controller's: one-sided spans `0..hi` (velocity and
    /// reachability rows) and short ones `lo..lo + 4` (obstacle rows), with
    /// random entries and signs (some exact zeros inside the spans too).
    fn rows<const N: usize>(seed: u64, k: usize) -> SMatrix<f64, N, N> {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut M = SMatrix::<f64, N, N>::zeros();
        for i in 0..k {
            let short = next() > 0.0;
            let a = ((next() * 0.5 + 0.5) * (N as f64 - 1.0)) as usize;
            let (lo, hi) = if short {
                (a.min(N - 4), (a.min(N - 4) + 4))
            } else {
                (0, (a + 1).max(2))
            };
            for r in lo..hi {
                let v = next();
                M[(r, i)] = if v.abs() < 0.05 { 0.0 } else { v };
            }
        }
        M
    }

    #[test]
    fn spans_give_the_bits_of_the_full_factor() {
        let (mut factored, mut declined) = (0, 0);
        for seed in 0..200 {
            for k in [5, 12, 20, 30] {
                let M = rows::<40>(seed, k);
                let mut T = SMatrix::<f64, 40, 40>::zeros();
                let ours = factor_gram(&M, k, &mut T);
                // The same factor from a workspace holding another one's
                // entries and NaN (a kept workspace is not cleared).
                let mut kept = SMatrix::<f64, 40, 40>::from_element(f64::NAN);
                let other = rows::<40>(seed + 1000, 30);
                factor_gram(&other, 30, &mut kept);
                let again = factor_gram(&M, k, &mut kept);
                assert_eq!(ours, again, "seed {seed}, k {k}");
                match reference(&M, k) {
                    Some(R) => {
                        assert!(ours, "seed {seed}, k {k}: declined");
                        for (a, b) in T.iter().zip(R.iter()) {
                            assert_eq!(a.to_bits(), b.to_bits(), "seed {seed}, k {k}");
                        }
                        // Of column `i < k` the entries `0..=i` are the
                        // guess's (the others are never read).
                        for i in 0..k {
                            for r in 0..=i {
                                let (a, b) = (kept[(r, i)], R[(r, i)]);
                                assert_eq!(a.to_bits(), b.to_bits(), "seed {seed}, k {k}");
                            }
                        }
                        factored += 1;
                    }
                    None => {
                        assert!(!ours, "seed {seed}, k {k}: accepted");
                        declined += 1;
                    }
                }
            }
        }
        // Both outcomes were exercised.
        assert!(factored > 100 && declined > 10, "{factored} {declined}");
    }

    #[test]
    fn small_sizes_take_all_entries() {
        for seed in 0..50 {
            let M = rows::<6>(seed, 4);
            let mut T = SMatrix::<f64, 6, 6>::zeros();
            let ours = factor_gram(&M, 4, &mut T);
            match reference(&M, 4) {
                Some(R) => {
                    assert!(ours);
                    for (a, b) in T.iter().zip(R.iter()) {
                        assert_eq!(a.to_bits(), b.to_bits(), "seed {seed}");
                    }
                }
                None => assert!(!ours),
            }
        }
    }
}
