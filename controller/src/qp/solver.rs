//! The solver's data: the Hessian, its factor `L^-1` and the settings
//! ([`DualActiveSetOf::new`]), and the products with `L^-1` and `L^-T`
//! every solve is built from.

use core::marker::PhantomData;

#[cfg(feature = "alloc")]
use nalgebra::Dyn;
use nalgebra::{ArrayStorage, Const, Dim, OMatrix, OVector, SMatrix, U1};

use super::settings::{HOT_START_MIN_NV, HessianError, PROX_EPS, QpSettings, proximal_capable};
use crate::linalg::{column, column_mut, columns, columns_mut, dot, dot_d};
use crate::solution::QpAllocator;
use nalgebra::{DefaultAllocator, allocator::Allocator};

/// The solver: the factored Hessian and the settings, for any dimension types
/// (see [`DualActiveSet`] for the static sizes). Build once per Hessian;
/// `solve` takes `&self`.
#[derive(Clone, Debug)]
pub struct DualActiveSetOf<NV: Dim, NC: Dim>
where
    DefaultAllocator: Allocator<NV, NV>,
{
    pub(super) H: OMatrix<f64, NV, NV>,
    /// `L^-1` with `H = L L'`: lower triangular, entries above the diagonal
    /// exactly zero.
    pub(super) Linv: OMatrix<f64, NV, NV>,
    /// Its transpose `J0 = L^-T`, where `J` starts in every solve from
    /// scratch: copied (one `memcpy`), not transposed, by each.
    pub(super) J0: OMatrix<f64, NV, NV>,
    /// `L^-1` (so `H`) is diagonal: products with `L^-1` and `L^-T` cost `NV`
    /// instead of `NV^2`.
    pub(super) linv_diag: bool,
    pub(super) settings: QpSettings,
    /// The proximal weight `eps` when `H` is only positive semidefinite
    /// (`L L' = H + eps I`, solved by proximal-point iterations,
    /// `qp/proximal.rs`); 0 for a positive definite `H`.
    pub(super) prox: f64,
    /// The row capacity is a parameter of the QPs solved, not of the solver's
    /// data.
    _nc: PhantomData<NC>,
}

/// [`DualActiveSetOf`] with the sizes as constants (stack only, `no_std`):
/// the controller's solver.
pub type DualActiveSet<const NV: usize, const NC: usize> = DualActiveSetOf<Const<NV>, Const<NC>>;

/// The run-time-sized instances (feature `alloc`): any number of variables
/// and rows, heap storage, the same code as the static ones.
#[cfg(feature = "alloc")]
pub type DualActiveSetDyn = DualActiveSetOf<Dyn, Dyn>;

impl<const NV: usize, const NC: usize> DualActiveSetOf<Const<NV>, Const<NC>> {
    /// A placeholder with `H = 0`, `L^-1 = 0` and zero tolerances, all storage
    /// zero, for `const` and `static` initialisers (e.g. an unconfigured
    /// controller). Not a solver: overwrite it with one from
    /// [`DualActiveSetOf::new`] before solving (its solves never panic but mean
    /// nothing).
    pub const PLACEHOLDER: Self = DualActiveSetOf {
        H: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
        Linv: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
        J0: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
        linv_diag: false,
        settings: QpSettings {
            tol_primal: 0.0,
            tol_dependence: 0.0,
            hot_start: false,
            max_iter: 0,
        },
        prox: 0.0,
        _nc: PhantomData,
    };
}

impl<NV: Dim, NC: Dim> DualActiveSetOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// Factors `H` (symmetric positive definite) once. A symmetric `H`
    /// that is only positive semidefinite (Cholesky fails, but not on
    /// `H + eps I` with [`PROX_EPS`](super::PROX_EPS) relative to its largest entry) is
    /// accepted where the proximal-point iterations are compiled in (from
    /// [`HOT_START_MIN_NV`] variables on for the static sizes, always for
    /// `Dyn`; see `qp/proximal.rs`); below that it is
    /// [`HessianError::NotPositiveDefinite`].
    pub fn new(H: &OMatrix<f64, NV, NV>, settings: QpSettings) -> Result<Self, HessianError> {
        if let (Some(nv), Some(nc)) = (NV::try_to_usize(), NC::try_to_usize()) {
            // Static sizes: a compile-time constant test.
            if nv == 0 || nv > usize::from(u16::MAX) || nc > usize::from(u16::MAX) {
                return Err(HessianError::BadSize);
            }
        }
        let n = H.nrows();
        if n == 0 || n > usize::from(u16::MAX) {
            return Err(HessianError::BadSize);
        }
        if H.as_slice().iter().any(|v| !v.is_finite()) {
            return Err(HessianError::NotFinite);
        }
        let scale = H.amax().max(f64::MIN_POSITIVE);
        // |H_ij - H_ji| for i > j; column `j` holds H_ij at `i` (column-major),
        // read with checked access (bounds the optimiser could not prove for
        // every NV, see nopanic/).
        let hs = H.as_slice();
        for (j, col) in columns(hs, n).enumerate() {
            for (i, &hij) in col.iter().enumerate().skip(j + 1) {
                let hji = column(hs, n, i)
                    .and_then(|c| c.get(j))
                    .copied()
                    .unwrap_or(hij);
                if (hij - hji).abs() > 1e-12 * scale {
                    return Err(HessianError::NotSymmetric);
                }
            }
        }
        let (chol, prox) = match nalgebra::linalg::Cholesky::new(H.clone()) {
            Some(chol) => (chol, 0.0),
            None if proximal_capable::<NV>() => regularised(H)?,
            None => return Err(HessianError::NotPositiveDefinite),
        };
        let L = chol.l();
        let (nv, _) = H.shape_generic();
        let mut J0 = OMatrix::<f64, NV, NV>::identity_generic(nv, nv);
        if !L.transpose().solve_upper_triangular_mut(&mut J0)
            || J0.as_slice().iter().any(|v| !v.is_finite())
        {
            return Err(HessianError::NotPositiveDefinite);
        }
        // J0 = L^-T with exact zeros below the diagonal, L^-1 its transpose.
        for (j, col) in columns_mut(J0.as_mut_slice(), n).enumerate() {
            for v in col.iter_mut().skip(j + 1) {
                *v = 0.0;
            }
        }
        let Linv = J0.transpose();
        let linv_diag = columns(Linv.as_slice(), n)
            .enumerate()
            .all(|(j, col)| col.iter().enumerate().all(|(k, &v)| k == j || v == 0.0));
        Ok(DualActiveSetOf {
            H: H.clone(),
            Linv,
            J0,
            linv_diag,
            settings,
            prox,
            _nc: PhantomData,
        })
    }

    /// The same solver with [`QpSettings::hot_start`] off (the marks then only
    /// decide which violated row is added first).
    pub fn without_hot_start(&self) -> Self {
        let mut s = self.clone();
        s.settings.hot_start = false;
        s
    }

    /// The same solver with the iteration limit [`QpSettings::max_iter`] set
    /// to `max_iter` (a copy of the factored Hessian, no factorisation).
    pub fn with_max_iter(&self, max_iter: u32) -> Self {
        let mut s = self.clone();
        s.settings.max_iter = max_iter;
        s
    }

    /// The proximal weight `eps` of a positive semidefinite `H` (the solves
    /// run proximal-point iterations on `H + eps I`, `qp/proximal.rs`); 0
    /// for a positive definite `H` (one solve, as always).
    pub fn proximal_weight(&self) -> f64 {
        self.prox
    }

    /// Whether solves run the proximal-point iterations: a constant `false`
    /// for the static sizes where they are not compiled in.
    #[inline(always)]
    pub(crate) fn proximal(&self) -> bool {
        proximal_capable::<NV>() && self.prox > 0.0
    }

    /// The Hessian this solver was built for.
    pub fn hessian(&self) -> &OMatrix<f64, NV, NV> {
        &self.H
    }

    /// The settings.
    pub fn settings(&self) -> &QpSettings {
        &self.settings
    }

    /// The number of variables as a dimension (a constant for the static
    /// sizes).
    #[inline(always)]
    pub(crate) fn nv(&self) -> NV {
        self.H.shape_generic().0
    }

    /// Whether the hot start is compiled in for this size (module docs): a
    /// constant for the static sizes; for `Dyn` the same threshold at run
    /// time, so both instances take the same path.
    #[inline(always)]
    pub(crate) fn hot_start_capable(&self) -> bool {
        NV::try_to_usize().unwrap_or(self.H.nrows()) >= HOT_START_MIN_NV
    }

    /// Whether equality rows are compiled in (module docs): from
    /// [`HOT_START_MIN_NV`] variables on for the static sizes, always for
    /// `Dyn`.
    #[inline(always)]
    pub(crate) fn equalities_capable(&self) -> bool {
        NV::try_to_usize().is_none_or(|n| n >= HOT_START_MIN_NV)
    }

    /// Objective `1/2 x'Hx + q'x`.
    pub fn objective(&self, q: &OVector<f64, NV>, x: &OVector<f64, NV>) -> f64 {
        let n = self.nv().value();
        let (Some(x), Some(q)) = (x.as_slice().get(..n), q.as_slice().get(..n)) else {
            return f64::NAN;
        };
        let mut xhx = 0.0;
        for (col, xj) in columns(self.H.as_slice(), n).zip(x.iter()) {
            xhx += xj * dot_d::<NV>(col, x);
        }
        0.5 * xhx + dot_d::<NV>(q, x)
    }

    /// The unconstrained minimiser `x = -H^-1 q = -L^-T L^-1 q`, where every
    /// solve from scratch starts.
    #[inline(always)]
    pub(super) fn unconstrained_minimiser(&self, q: &OVector<f64, NV>) -> OVector<f64, NV> {
        let mut x = self.linvt_mul(self.linv_mul(q.as_slice()).as_slice());
        for v in x.as_mut_slice() {
            *v = -*v;
        }
        x
    }

    /// `L^-1 g` (`= J0' g`) as column axpys (no reductions);
    /// `NV` products when `H` is diagonal. Entries of `g` beyond `NV` are
    /// not read; a shorter `g` gives 0.
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub(crate) fn linv_mul(&self, g: &[f64]) -> OVector<f64, NV> {
        let nv = self.nv();
        let n = nv.value();
        let mut w = OVector::<f64, NV>::zeros_generic(nv, U1);
        let Some(g) = g.get(..n) else {
            return w;
        };
        let ws = w.as_mut_slice();
        let linv = self.Linv.as_slice();
        // The diagonal test outside the loops, and each column by `column`
        // (whose length is visibly `n`): for the static sizes the axpys
        // unroll with `w` in registers.
        if self.linv_diag {
            for (k, (wk, &gk)) in ws.iter_mut().zip(g).enumerate() {
                if let Some(&c) = column(linv, n, k).and_then(|col| col.get(k)) {
                    *wk = c * gk;
                }
            }
        } else if NV::try_to_usize().is_none() {
            // Run-time sizes: the triangle only (rows `k..` of column `k`).
            // The products skipped are exact zeros, which would leave `w`
            // as it is (it starts at +0 and never becomes -0), so the bits
            // are those of the full-length loop for finite `g`.
            for (k, &gk) in g.iter().enumerate() {
                let (Some(col), Some(wt)) =
                    (column(linv, n, k).and_then(|c| c.get(k..)), ws.get_mut(k..))
                else {
                    break;
                };
                for (wi, c) in wt.iter_mut().zip(col) {
                    *wi += c * gk;
                }
            }
        } else {
            for (k, &gk) in g.iter().enumerate() {
                let Some(col) = column(linv, n, k) else {
                    break;
                };
                // zeros above the diagonal included: fixed length, vectorised
                for (wi, c) in ws.iter_mut().zip(col) {
                    *wi += c * gk;
                }
            }
        }
        w
    }

    /// `L^-T w` (`= J0 w`); `NV` products when `H` is diagonal.
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub(crate) fn linvt_mul(&self, w: &[f64]) -> OVector<f64, NV> {
        let nv = self.nv();
        let n = nv.value();
        let mut x = OVector::<f64, NV>::zeros_generic(nv, U1);
        let Some(w) = w.get(..n) else {
            return x;
        };
        for (k, (xk, col)) in x
            .as_mut_slice()
            .iter_mut()
            .zip(columns(self.Linv.as_slice(), n))
            .enumerate()
        {
            *xk = if self.linv_diag {
                col.get(k).copied().unwrap_or(0.0) * w.get(k).copied().unwrap_or(0.0)
            } else if NV::try_to_usize().is_none() {
                // Run-time sizes: from the even index at or above the
                // diagonal (the products skipped are exact zeros, which
                // leave both partial sums at +0; each index keeps its
                // parity, hence its partial sum): the bits of `dot`.
                let k0 = k & !1;
                match (col.get(k0..), w.get(k0..)) {
                    (Some(c), Some(wt)) => dot_d::<NV>(c, wt),
                    _ => 0.0,
                }
            } else {
                dot(col, w) // zeros above the diagonal included: no branches
            };
        }
        x
    }
}

/// The Cholesky factor of `H + eps I` and `eps`, for an `H` without one of
/// its own (symmetric and finite, checked by the caller).
pub(super) fn regularised<NV: Dim>(
    H: &OMatrix<f64, NV, NV>,
) -> Result<(nalgebra::linalg::Cholesky<f64, NV>, f64), HessianError>
where
    DefaultAllocator: nalgebra::allocator::Allocator<NV, NV>,
{
    let amax = H.amax();
    let eps = PROX_EPS * if amax > 0.0 { amax } else { 1.0 };
    let n = H.nrows();
    let mut Hr = H.clone();
    for j in 0..n {
        if let Some(d) = column_mut(Hr.as_mut_slice(), n, j).and_then(|c| c.get_mut(j)) {
            *d += eps;
        }
    }
    let chol = nalgebra::linalg::Cholesky::new(Hr).ok_or(HessianError::NotPositiveDefinite)?;
    Ok((chol, eps))
}
