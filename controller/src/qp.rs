//! Dense dual active-set QP solver (Goldfarb–Idnani family), no heap.
//!
//! Solves
//!
//! ```text
//! minimise   1/2 x' H x + q' x
//! subject to G x <= h          (m rows, m <= NC)
//! ```
//!
//! for a fixed symmetric positive-definite `H` of size `NV x NV`. The Hessian is
//! factored once in [`DualActiveSet::new`] (`H = L L'`, and `L^-1` is kept, with a
//! flag for a diagonal `H` that makes products with it cost `NV`);
//! each [`DualActiveSet::solve`] starts from the unconstrained minimiser
//! `x = -H^-1 q` and adds violated constraints one at a time, dropping constraints
//! whose multiplier would turn negative, exactly as in Goldfarb & Idnani (1983,
//! "A numerically stable dual method for solving strictly convex quadratic
//! programs"). The factorisation of the active set is kept as `J = L^-T Q` and the
//! upper-triangular `R` of `L^-1 N_A = Q [R; 0]`, updated by one Householder
//! reflection on every add and by Givens rotations on every drop (no
//! re-factorisation, no normal equations; `qp/orthogonal.rs`). The iteration
//! itself is written once for this solver and the least-distance path of
//! [`crate::ldp`] (`active_set.rs`).
//!
//! Cost per solve: `m` row norms, one `H^-1` row norm (`|L^-1 g_i|`) per row the
//! first time it is found violated, and per add or drop `O(m NV + NV^2)`. When `G`
//! is the same over many solves (only `q` and `h` change), the row norms can be
//! computed once with [`DualActiveSet::prepare_rows`] and passed to
//! [`DualActiveSet::solve_prepared`]; a series of solves of the same rows
//! with other right-hand sides (the relaxation's probes) shares them and
//! continues each from the last one's factor with
//! [`DualActiveSet::solve_reprobe`] (`qp/reprobe.rs`). The kernels run over slices whose
//! lengths are the dimensions (the constants `NV`, `NC` for the static
//! sizes), so the compiler unrolls and vectorises them without bounds checks
//! there; see `docs/solvers.md` for the measurements that chose them.
//!
//! # One algorithm, any size
//!
//! Written once, generic over nalgebra's dimension types: `NV` (variables)
//! and `NC` (row capacity) are [`Dim`]s. With `Const<N>` every buffer is a
//! fixed-size array on the stack (no heap, `no_std`): the controller and the
//! firmware use this through the aliases [`DualActiveSet`], [`DenseQp`],
//! [`QpSolution`] and [`RowNorms`], whose sizes are `const` parameters. With
//! `Dyn` (feature `alloc`, never in the `no_std` build) the sizes are chosen
//! at run time and the buffers live on the heap: `DualActiveSetDyn`,
//! `DenseQpDyn`, `QpSolutionDyn`, `RowNormsDyn`. Both run the same code,
//! operation for operation, so they give bit-identical results on the same
//! data.
//!
//! # Equality rows
//!
//! The first `me` rows of a [`DenseQpOf`] may be equalities `g_i'x = h_i`
//! ([`DenseQpOf::push_equality`]). They enter the active set before the
//! first scan, are never dropped, and their multipliers have either sign
//! (DAQP's and qpOASES' treatment); dependent equality rows are checked for
//! consistency (redundant, or a Farkas certificate). They are compiled in
//! with the hot start: from [`HOT_START_MIN_NV`] variables on for the static
//! sizes, always for `Dyn`; a static instance below that answers a QP with
//! equality rows with [`QpStatus::NumericalError`].
//!
//! Iteration count = number of adds plus drops; it never exceeds the budget,
//! [`QpSettings::max_iter`] (with the tolerances; `solve_selected` also takes
//! a caller's remaining budget). Every loop is bounded by `NV`, `NC` or the
//! budget.
//!
//! Warm start: the caller may mark rows it expects to be active (for example the
//! previous cycle's active set, shifted). Among the violated rows the solver adds
//! a marked one first; each choice scans the marked rows alone first and all
//! rows only when none of them is violated (the same choice without the dot
//! products of the other rows, so the same path and results bit for bit). From
//! [`HOT_START_MIN_NV`] variables on, with [`QpSettings::hot_start`] (the
//! default), the marked rows also enter the active set together before the
//! first scan, as in DAQP's and qpOASES' warm start by active set: each is added
//! to the factorisation (no scan, no step), the minimiser on them held as
//! equalities and its multipliers are formed, and the row with the most negative
//! multiplier is dropped until none is left. That is the pair the dual method
//! starts from and keeps (`x` optimal on the active rows, multipliers `>= 0`),
//! so when the marks are right one scan finds nothing violated; on the
//! controller's long horizons it removes most row scans (`docs/horizon.md`).
//! Any valid starting pair and any violated row are valid choices in the dual
//! method, so the marks change the path (usually shortening it), and with the
//! hot start the rounding, never the solution.
//!
//! Infeasibility: a violated row whose normal lies in the span of the active
//! normals and for which no active multiplier can decrease proves the constraint
//! set empty (Goldfarb & Idnani, step 2(c)(i)); the solver reports
//! [`QpStatus::Infeasible`].
#![allow(non_snake_case)]

use core::marker::PhantomData;

#[cfg(feature = "alloc")]
use nalgebra::Dyn;
use nalgebra::allocator::Allocator;
use nalgebra::{ArrayStorage, Const, DefaultAllocator, Dim, OMatrix, OVector, SMatrix, U1};

use crate::active_set;
use crate::linalg::{column, columns, columns_mut, dot, dot_d};
#[cfg(feature = "alloc")]
pub use crate::solution::QpSolutionDyn;
pub use crate::solution::{QpAllocator, QpSolution, QpSolutionOf, QpStatus};

/// The checks every solve starts with, written once for
/// `DualActiveSetOf::solve_with` and the proximal iterations
/// (`qp/proximal.rs`): binds the names after `=>` (the variables and row
/// capacity as dimensions, the rows used, the linear term as a slice, the
/// primal tolerance, the equality rows at the head, 0 where they are not
/// compiled in, and the rows blocked from the start: `excluded` and the zero
/// equality rows), or returns the answer from the enclosing function when
/// the solve ends there (sizes, a non-finite `q`, `h` or row, an equality
/// row where they are not compiled in, a zero row that contradicts itself).
/// A macro, not a function: the static instances compile exactly as with the
/// checks written out in place.
macro_rules! solve_start {
    ($s:ident, $qp:ident, $qv:expr, $hv:ident, $excluded:ident, $norms:ident =>
     $nv:ident, $nc:ident, $m:ident, $q:ident, $tol:ident, $me:ident, $blocked:ident) => {
        let $nv = $s.nv();
        let n = $nv.value();
        let $nc = $qp.h.shape_generic().0;
        let $m = $qp.m.min($nc.value());
        let $q = $qv.as_slice();
        let (h, norm2) = ($hv.as_slice(), $norms.norm2.as_slice());
        if h.len() != $nc.value()
            || norm2.len() != $nc.value()
            || $norms.inv_hnorm.len() != $nc.value()
        {
            return $crate::active_set::stopped(
                $nv,
                $nc,
                $crate::solution::QpStatus::NumericalError,
            );
        }
        if !$norms.finite
            || $qp.gt.nrows() != n
            || $q.len() != n
            || !$q.iter().all(|v| v.is_finite())
            || !h
                .iter()
                .zip($excluded.as_slice().iter())
                .take($m)
                .all(|(v, &out)| out || v.is_finite())
        {
            return $crate::active_set::stopped(
                $nv,
                $nc,
                $crate::solution::QpStatus::NumericalError,
            );
        }
        let $tol = $s.settings.tol_primal;
        // Equality rows only where they are compiled in (module docs): for
        // the small static sizes `me` is the constant 0 from here on.
        let capable = $s.equalities_capable();
        if !capable && $qp.me > 0 {
            return $crate::active_set::stopped(
                $nv,
                $nc,
                $crate::solution::QpStatus::NumericalError,
            );
        }
        let $me = if capable { $qp.me.min($m) } else { 0 };
        let zero_infeasible = h
            .iter()
            .zip(norm2.iter())
            .zip($excluded.as_slice().iter())
            .take($m)
            .enumerate()
            .position(|(i, ((&hi, &n2), &out))| {
                !out && n2 <= $crate::qp::ZERO_ROW2
                    && $crate::active_set::zero_row_contradicts(hi, $tol, i < $me)
            });
        if let Some(i) = zero_infeasible {
            // Nothing satisfies it: y = e_i (or -e_i) certifies it.
            let hi = h.get(i).copied().unwrap_or(0.0);
            return $crate::active_set::zero_row_infeasible($nv, $nc, i, hi);
        }
        let mut $blocked = $excluded;
        // Zero rows are never added (an equality zero row holds here).
        for (b, &n2) in $blocked
            .as_mut_slice()
            .iter_mut()
            .zip(norm2.iter())
            .take($me)
        {
            if n2 <= $crate::qp::ZERO_ROW2 {
                *b = true;
            }
        }
    };
}

mod backend;
mod bounds;
mod dense;
mod guess;
mod orthogonal;
mod proximal;
mod reprobe;
mod resolve;
mod spans;
pub use backend::{OwnSolver, QpBackend};
#[cfg(feature = "alloc")]
pub use bounds::SimpleBoundsDyn;
pub use bounds::{SimpleBounds, SimpleBoundsOf};
#[cfg(feature = "alloc")]
pub use dense::DenseQpDyn;
pub use dense::{DenseQp, DenseQpOf};
use orthogonal::Orthogonal;
use proximal::proximal_capable;
use reprobe::Carry;
pub use reprobe::{Reprobe, ReprobeOf};
use resolve::Resumed;
mod settings;
pub use proximal::{PROX_EPS, PROX_MAX_OUTER, PROX_TOL};
pub use settings::{HessianError, QpSettings};

/// Rows whose squared Euclidean norm is not above this (it is 0 for an exactly
/// zero row or one whose squares underflow, `|g| < ~1e-162`) are treated as zero
/// rows: satisfied when `h_i >= -tol`, infeasible otherwise.
pub(crate) const ZERO_ROW2: f64 = 0.0;

/// Smallest number of variables for which [`QpSettings::hot_start`] and
/// equality rows are compiled into a static instance (the controller's
/// horizons `N >= 8`; `Dyn` instances use the same threshold at run time).
/// Below it, scanning the marked rows first gets most of the gain, and the
/// hot start's code (3.8 KiB of Thumb at `NV = 6`) would not fit the
/// firmware's 64 KiB of flash (`docs/horizon.md`).
pub const HOT_START_MIN_NV: usize = 16;

/// Per-row data of a constraint matrix `G` used by a solve: squared Euclidean
/// norms `|g_i|^2` and reciprocal norms in the metric of `H^-1`,
/// `1 / |L^-1 g_i|` (both 0 for a zero row). Built by
/// [`DualActiveSetOf::prepare_rows`] for [`DualActiveSetOf::solve_prepared`].
#[derive(Clone, Debug)]
pub struct RowNormsOf<NC: Dim>
where
    DefaultAllocator: Allocator<NC>,
{
    /// `|g_i|^2`, in the units of `G` squared (no square root or division, so
    /// the pass over all rows is cheap; the violation test squares the slack).
    norm2: OVector<f64, NC>,
    /// `1 / |L^-1 g_i|`, 0 = not computed yet.
    inv_hnorm: OVector<f64, NC>,
    /// Rows covered.
    m: usize,
    /// Every entry of the covered rows is finite.
    finite: bool,
}

/// [`RowNormsOf`] with the row capacity as a constant.
pub type RowNorms<const NC: usize> = RowNormsOf<Const<NC>>;

impl<NC: Dim> RowNormsOf<NC>
where
    DefaultAllocator: Allocator<NC>,
{
    /// Squared Euclidean norms of the used rows of `qp` (H^-1 norms not
    /// computed).
    fn euclidean<NV: Dim>(qp: &DenseQpOf<NV, NC>) -> Self
    where
        DefaultAllocator: Allocator<NV> + Allocator<NV, NC>,
    {
        let nc = qp.h.shape_generic().0;
        let m = qp.m.min(nc.value());
        let mut rows = RowNormsOf {
            norm2: OVector::zeros_generic(nc, U1),
            inv_hnorm: OVector::zeros_generic(nc, U1),
            m,
            finite: true,
        };
        for (g, n2) in columns(qp.gt.as_slice(), qp.gt.nrows())
            .zip(rows.norm2.as_mut_slice().iter_mut())
            .take(m)
        {
            *n2 = dot_d::<NV>(g, g);
            // A NaN or infinite entry makes `n2` non-finite, and so does a row
            // whose squared norm overflows (|g| > ~1e154): both are numerical
            // errors.
            if !n2.is_finite() {
                rows.finite = false;
            }
        }
        rows
    }

    /// [`RowNormsOf::euclidean`] with `|g_i|^2 = 1` for the bound rows of
    /// `bounds` (row codes of [`SimpleBoundsOf`]): no dot product for them.
    fn euclidean_except<NV: Dim>(qp: &DenseQpOf<NV, NC>, bounds: &SimpleBoundsOf<NC>) -> Self
    where
        DefaultAllocator: Allocator<NV> + Allocator<NV, NC>,
    {
        let nc = qp.h.shape_generic().0;
        let m = qp.m.min(nc.value());
        let mut rows = RowNormsOf {
            norm2: OVector::zeros_generic(nc, U1),
            inv_hnorm: OVector::zeros_generic(nc, U1),
            m,
            finite: true,
        };
        for ((g, n2), &c) in columns(qp.gt.as_slice(), qp.gt.nrows())
            .zip(rows.norm2.as_mut_slice().iter_mut())
            .zip(bounds.code.as_slice())
            .take(m)
        {
            *n2 = if c != 0 { 1.0 } else { dot_d::<NV>(g, g) };
            if !n2.is_finite() {
                rows.finite = false;
            }
        }
        rows
    }
}

/// The solver: the factored Hessian and the settings, for any dimension types
/// (see [`DualActiveSet`] for the static sizes). Build once per Hessian;
/// `solve` takes `&self`.
#[derive(Clone, Debug)]
pub struct DualActiveSetOf<NV: Dim, NC: Dim>
where
    DefaultAllocator: Allocator<NV, NV>,
{
    H: OMatrix<f64, NV, NV>,
    /// `L^-1` with `H = L L'`: lower triangular, entries above the diagonal
    /// exactly zero. Its transpose `J0 = L^-T` starts `J` in every solve.
    Linv: OMatrix<f64, NV, NV>,
    /// `L^-1` (so `H`) is diagonal: products with `L^-1` and `L^-T` cost `NV`
    /// instead of `NV^2`.
    linv_diag: bool,
    settings: QpSettings,
    /// The proximal weight `eps` when `H` is only positive semidefinite
    /// (`L L' = H + eps I`, solved by proximal-point iterations,
    /// `qp/proximal.rs`); 0 for a positive definite `H`.
    prox: f64,
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
/// [`RowNormsOf`] with run-time sizes (feature `alloc`).
#[cfg(feature = "alloc")]
pub type RowNormsDyn = RowNormsOf<Dyn>;

impl<const NV: usize, const NC: usize> DualActiveSetOf<Const<NV>, Const<NC>> {
    /// A placeholder with `H = 0`, `L^-1 = 0` and zero tolerances, all storage
    /// zero, for `const` and `static` initialisers (e.g. an unconfigured
    /// controller). Not a solver: overwrite it with one from
    /// [`DualActiveSetOf::new`] before solving (its solves never panic but mean
    /// nothing).
    pub const PLACEHOLDER: Self = DualActiveSetOf {
        H: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
        Linv: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
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
    /// `H + eps I` with [`PROX_EPS`] relative to its largest entry) is
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
            None if proximal_capable::<NV>() => proximal::regularised(H)?,
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
        // L^-1 with exact zeros above the diagonal.
        let mut Linv = J0.transpose();
        for (j, col) in columns_mut(Linv.as_mut_slice(), n).enumerate() {
            for v in col.iter_mut().take(j) {
                *v = 0.0;
            }
        }
        let linv_diag = columns(Linv.as_slice(), n)
            .enumerate()
            .all(|(j, col)| col.iter().enumerate().all(|(k, &v)| k == j || v == 0.0));
        Ok(DualActiveSetOf {
            H: H.clone(),
            Linv,
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
            xhx += xj * dot(col, x);
        }
        0.5 * xhx + dot(q, x)
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

    /// Solves the QP `qp` with at most [`QpSettings::max_iter`] adds plus
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
    /// [`QpStatus::NumericalError`].
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
        let mut carry = Carry::fresh(self.nv());
        self.solve_with(
            qp, &qp.q, &qp.h, excluded, &mut rows, codes, prefer, max_iter, &mut carry,
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
    /// (else [`QpStatus::NumericalError`]). At most `budget` adds plus drops
    /// (a caller's remaining budget, as the relaxation's budget of a cycle),
    /// and at most [`QpSettings::max_iter`].
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

    /// The per-row data of `qp`'s constraint matrix that [`DualActiveSetOf::solve`]
    /// otherwise computes in every call (`m` Euclidean and `m` H^-1 row norms):
    /// prepare it once when `G` stays the same over many solves (only `q` and `h`
    /// change, as in a linear MPC with fixed constraints) and pass it to
    /// [`DualActiveSetOf::solve_prepared`].
    pub fn prepare_rows(&self, qp: &DenseQpOf<NV, NC>) -> RowNormsOf<NC> {
        let mut rows = RowNormsOf::euclidean(qp);
        let m = rows.m;
        for ((g, &n2), inv_hn) in columns(qp.gt.as_slice(), qp.gt.nrows())
            .zip(rows.norm2.as_slice().iter())
            .zip(rows.inv_hnorm.as_mut_slice().iter_mut())
            .take(m)
        {
            if n2 > ZERO_ROW2 {
                *inv_hn = self.inv_hnorm(g, n2);
            }
        }
        rows
    }

    /// [`DualActiveSetOf::solve`] with the row data prepared by
    /// [`DualActiveSetOf::prepare_rows`] from a QP with the same rows of `G` (same
    /// `m`; `q` and `h` may differ). Same result as `solve`, less work per call.
    /// A `rows` prepared for a different `m` gives [`QpStatus::NumericalError`].
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
    /// `qp` with its `h`, from scratch, at most [`QpSettings::max_iter`].
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
        let mut carry = Carry::scratch(self);
        self.solve_with(
            qp,
            &qp.q,
            &qp.h,
            excluded,
            rows,
            (),
            prefer,
            max_iter,
            &mut carry,
        )
    }

    /// `1 / |L^-1 g|` for a row with `|g|^2 = n2 > 0`.
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    fn inv_hnorm(&self, g: &[f64], n2: f64) -> f64 {
        let w = self.linv_mul(g);
        let hn = crate::linalg::sqrt(dot_d::<NV>(w.as_slice(), w.as_slice()));
        // L^-1 is nonsingular, so hn > 0 for a non-zero row (barring underflow,
        // where the Euclidean norm stands in).
        if hn > 0.0 {
            1.0 / hn
        } else {
            1.0 / crate::linalg::sqrt(n2)
        }
    }

    /// `1 / |L^-1 e_j|`, the norm of column `j` of `L^-1`: the bits of
    /// [`DualActiveSetOf::inv_hnorm`] for the row `+-e_j` (the products
    /// with its zero entries are exact zeros).
    #[inline(always)]
    fn inv_hnorm_unit(&self, j: usize) -> f64 {
        let n = self.nv().value();
        let col = column(self.Linv.as_slice(), n, j).unwrap_or(&[]);
        let hn = crate::linalg::sqrt(dot_d::<NV>(col, col));
        if hn > 0.0 { 1.0 / hn } else { 1.0 }
    }

    /// The solve proper, with the linear term `q` (`qp.q`, or the proximal
    /// iteration's; the objective is the one of `qp.q`), the right-hand side
    /// `h` (`qp.h` or another), the rows `excluded[i]` left out, the
    /// Euclidean row norms in `rows` and the H^-1 norms there or computed on
    /// demand (0 = not yet), the bound rows `bounds` (`qp/bounds.rs`; `()`
    /// for none), the factor in `carry` (from scratch, or from the active
    /// rows of the solve before, `qp/reprobe.rs`; left there for the next).
    #[allow(clippy::too_many_arguments)]
    fn solve_with<Bd: bounds::BoundRows>(
        &self,
        qp: &DenseQpOf<NV, NC>,
        qv: &OVector<f64, NV>,
        hv: &OVector<f64, NC>,
        excluded: OVector<bool, NC>,
        norms: &mut RowNormsOf<NC>,
        bounds: Bd,
        prefer: &[bool],
        max_iter: u32,
        carry: &mut Carry<NV>,
    ) -> QpSolutionOf<NV, NC> {
        solve_start!(self, qp, qv, hv, excluded, norms => nv, nc, m, _q, tol, me, blocked);
        let pref = active_set::marks(nc, prefer);
        // Whether any row is marked (on hosts; on bare-metal targets the
        // iteration's own test of the marks alone, which is shorter there).
        let marked = cfg!(target_os = "none") || prefer.iter().any(|&p| p);
        // From scratch, or from the factor `carry` holds (`qp/reprobe.rs`).
        let (x, resumed_drops) = match carry.start(self, qv, hv, &mut blocked, me, max_iter) {
            Ok(start) => start,
            Err(status) => return active_set::stopped(nv, nc, status),
        };
        let Carry {
            J, R, kept, valid, ..
        } = &mut *carry;
        let mut d = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut factor = Resumed {
            inner: Orthogonal {
                solver: self,
                rows: &qp.gt,
                h: hv,
                norm2: &norms.norm2,
                inv_hnorm: &mut norms.inv_hnorm,
                tol2: tol * tol,
                x,
                J,
                R,
                d: &mut d,
                z: OVector::zeros_generic(nv, U1),
                dependent: false,
                span: None,
                reorder: false,
                bounds,
            },
            kept: if *valid { Some(&*kept) } else { None },
        };
        // Rows left out are never scanned: they start (and stay) blocked as if
        // active, but never enter the active list.
        let hot = self.settings.hot_start;
        // Without equality rows (the controller's QPs) the iteration is
        // compiled with `me = 0` as a constant: no equality phase, ratio test
        // and drops from the first active row (host: 3-5 % per `step` at
        // N = 10, 20).
        macro_rules! iterate {
            ($factor:expr) => {
                if me == 0 {
                    active_set::iterate($factor, nv, m, 0, blocked, &pref, marked, max_iter, hot)
                } else {
                    active_set::iterate($factor, nv, m, me, blocked, &pref, marked, max_iter, hot)
                }
            };
        }
        // On hosts, from 16 variables on, a start from scratch (every solve
        // but a resumed probe) iterates on the plain factor: no resume hook
        // and no test for spans in its scan (3 % of `solve` on LIPMWALK); the
        // same bits. Smaller sizes (no spans compiled in; a second copy of
        // the iteration cost the N = 3 step 2 %) and bare-metal targets: one
        // compiled iteration.
        let plain = cfg!(not(target_os = "none")) && proximal_capable::<NV>();
        let it = if plain && factor.kept.is_none() {
            iterate!(&mut factor.inner)
        } else {
            iterate!(&mut factor)
        };
        let x = factor.inner.x;
        let Some(it) = it else {
            // The orthogonal factor never asks for a restart.
            carry.valid = false;
            return active_set::stopped(nv, nc, QpStatus::NumericalError);
        };
        carry.keep(&it);
        let objective = self.objective(&qp.q, &x);
        let mut sol = it.solution(nc, x, objective, |_| 1.0);
        sol.iterations = sol.iterations.saturating_add(resumed_drops);
        sol
    }
}

#[cfg(test)]
mod tests;
