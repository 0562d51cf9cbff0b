//! The hot start's guess ([`ActiveSetFactor::hot_guess`]): the minimiser
//! on the marked rows held as equalities from their normal equations,
//! `K lambda = G_A x0 - h_A` with `K = M M'`, `m_j = L^-1 g_j`, factored by
//! `qp/gram.rs`; `x = x0 - L^-T M' lambda`, kept when every row holds and
//! every multiplier is `>= 0`. Cheaper than entering the rows one add at a
//! time (`qp/step.rs`), which is only needed if an iteration follows.

use nalgebra::{DefaultAllocator, Dim, OMatrix, OVector};

use super::bounds::BoundRows;
use super::gram::factor_gram;
use super::kept::Resume;
use super::orthogonal::Orthogonal;
use crate::linalg::{column, columns, columns_in, columns_mut, copy, dot_d};
use crate::solution::QpAllocator;

impl<NV: Dim, NC: Dim, Bd: BoundRows, Rs: Resume<NV>> Orthogonal<'_, NV, NC, Bd, Rs>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// [`ActiveSetFactor::hot_guess`] with `M` and `T` in `M`, `T`
    /// (written where read, whatever they hold).
    #[inline(always)]
    pub(super) fn guess_in(
        &mut self,
        M: &mut OMatrix<f64, NV, NV>,
        T: &mut OMatrix<f64, NV, NV>,
        act: &[u16],
        k: usize,
        mult: &mut [f64],
        blocked: &[bool],
    ) -> bool {
        let nv = self.solver.nv();
        let n = nv.value();
        let k = k.min(n);
        // Column j of `M` (NV x NV, column-major) is m_j = L^-1 g_j (the
        // columns `0..k` written here).
        let mut c = OVector::<f64, NV>::zeros_generic(nv, nalgebra::U1);
        for (&a, (mcol, cj)) in act
            .iter()
            .zip(columns_mut(M.as_mut_slice(), n).zip(c.as_mut_slice().iter_mut()))
            .take(k)
        {
            let Some((g, ha)) = self.row(usize::from(a)) else {
                return false;
            };
            copy(mcol, self.solver.linv_mul(g).as_slice());
            *cj = dot_d::<NV>(g, self.x.as_slice()) - ha;
        }
        let Ms = M.as_slice();
        // K = C C' (lower C; `T = C'`, `qp/guess.rs`).
        if !factor_gram(M, k, T) {
            return false;
        }
        let Ts = T.as_slice();
        let diag = |i: usize| {
            column(Ts, n, i)
                .and_then(|t| t.get(i))
                .copied()
                .unwrap_or(0.0)
        };
        // C y = c (row `i` of `C` is column `i` of `T`).
        let mut y = OVector::<f64, NV>::zeros_generic(nv, nalgebra::U1);
        for (i, ti) in columns(Ts, n).enumerate().take(k) {
            let mut s = c.get(i).copied().unwrap_or(0.0);
            for (a, yl) in ti.iter().zip(y.as_slice()).take(i) {
                s -= a * yl;
            }
            if let Some(yi) = y.get_mut(i) {
                *yi = s / diag(i);
            }
        }
        // C' lambda = y (column `i` of `C` is entry `i` of the columns of
        // `T` after `i`).
        let mut lambda = OVector::<f64, NV>::zeros_generic(nv, nalgebra::U1);
        for i in (0..k).rev() {
            let mut s = y.get(i).copied().unwrap_or(0.0);
            let after = lambda.as_slice().get(i + 1..k).unwrap_or(&[]);
            for (tl, ll) in columns_in(Ts, n, i + 1, k).zip(after) {
                s -= tl.get(i).copied().unwrap_or(0.0) * ll;
            }
            if let Some(li) = lambda.get_mut(i) {
                *li = s / diag(i);
            }
        }
        if !lambda.as_slice().iter().all(|&l| l >= 0.0 && l.is_finite()) {
            return false;
        }
        // x = x0 - L^-T M' lambda.
        let mut w = OVector::<f64, NV>::zeros_generic(nv, nalgebra::U1);
        for (col, &l) in columns(Ms, n).zip(lambda.as_slice().iter()).take(k) {
            for (wk, &mk) in w.as_mut_slice().iter_mut().zip(col) {
                *wk += l * mk;
            }
        }
        let step = self.solver.linvt_mul(w.as_slice());
        let x0 = self.x.clone();
        for (xk, sk) in self.x.as_mut_slice().iter_mut().zip(step.as_slice().iter()) {
            *xk -= sk;
        }
        // Every row must hold (the marked ones do, to rounding; if rounding
        // says otherwise the guess is dropped).
        let mut holds = true;
        // (A zero row's rate, `+0`, holds.)
        for (i, &b) in blocked.iter().enumerate() {
            if self
                .violation_over::<false>(i, b)
                .is_some_and(|s| s < 0.0 || s.is_nan())
            {
                holds = false;
                break;
            }
        }
        if !holds || !self.x.as_slice().iter().all(|v| v.is_finite()) {
            self.x = x0;
            return false;
        }
        for (m, &l) in mult.iter_mut().zip(lambda.as_slice().iter()) {
            *m = l;
        }
        true
    }
}
