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
//! factored once in [`DualActiveSetOf::new`] (`H = L L'`, and `L^-1` is kept, with a
//! flag for a diagonal `H` that makes products with it cost `NV`);
//! each [`DualActiveSetOf::solve`] starts from the unconstrained minimiser
//! `x = -H^-1 q` and adds violated constraints one at a time, dropping constraints
//! whose multiplier would turn negative, exactly as in Goldfarb & Idnani (1983,
//! "A numerically stable dual method for solving strictly convex quadratic
//! programs"). The factorisation of the active set is kept as `J = L^-T Q` and the
//! upper-triangular `R` of `L^-1 N_A = Q [R; 0]`, updated by one Householder
//! reflection on every add and by Givens rotations on every drop (no
//! re-factorisation, no normal equations).
//!
//! # One algorithm, any size
//!
//! The solver is written once, generic over nalgebra's dimension types: `NV`
//! (variables) and `NC` (row capacity) are [`Dim`]s. With `Const<N>` every
//! buffer is a fixed-size array on the stack (no heap, `no_std`): this is what
//! the controller and the firmware use, through the aliases [`DualActiveSet`],
//! [`DenseQp`], [`QpSolution`] and [`RowNorms`] that take the sizes as `const`
//! parameters. With `Dyn` (feature `alloc`, never in the `no_std` build) the
//! sizes are chosen at run time and the buffers live on the heap: the aliases
//! `DualActiveSetDyn`, `DenseQpDyn`, `QpSolutionDyn`, `RowNormsDyn`. Both run
//! the same code, operation for operation, so they give bit-identical results
//! on the same data.
//!
//! Cost per solve: `m` row norms, one `H^-1` row norm (`|L^-1 g_i|`) per row the
//! first time it is found violated, and per add or drop `O(m NV + NV^2)`. When `G`
//! is the same over many solves (only `q` and `h` change), the row norms can be
//! computed once with [`DualActiveSetOf::prepare_rows`] and passed to
//! [`DualActiveSetOf::solve_prepared`]. The kernels run over contiguous slices
//! whose lengths are the dimensions (constants for `Const<N>`), so the compiler
//! unrolls and vectorises them for the static sizes; see `docs/solvers.md` for
//! the measurements that chose them.
//!
//! Iteration count = number of adds plus drops; it never exceeds the budget passed
//! to `solve`. Every loop is bounded by `NV`, `NC` or the budget.
//!
//! Cheap case: when the unconstrained minimiser satisfies every row, the solve
//! returns it after one pass over the rows (0 iterations, no factor update).
//!
//! Warm start: the caller may mark rows it expects to be active (for example the
//! previous cycle's active set). Among the violated rows the solver adds a marked
//! one first. Any violated row is a valid choice in the dual method, so the marks
//! change the path (usually shortening it), never the solution.
//!
//! Infeasibility: a violated row whose normal lies in the span of the active
//! normals and for which no active multiplier can decrease proves the constraint
//! set empty (Goldfarb & Idnani, step 2(c)(i)); the solver reports
//! [`QpStatus::Infeasible`].
#![allow(non_snake_case)]

use core::marker::PhantomData;

use nalgebra::allocator::Allocator;
use nalgebra::{
    ArrayStorage, Const, DefaultAllocator, Dim, OMatrix, OVector, SMatrix, SVector, U1,
};

/// Rows whose squared Euclidean norm is not above this (it is 0 for an exactly
/// zero row or one whose squares underflow, `|g| < ~1e-162`) are treated as zero
/// rows: satisfied when `h_i >= -tol`, infeasible otherwise.
pub(crate) const ZERO_ROW2: f64 = 0.0;

/// The allocations the solver needs for `NV` variables and `NC` rows: every
/// `DefaultAllocator` over `Const` sizes has them (no heap), and so has the
/// one over `Dyn` with nalgebra's `alloc` feature.
pub trait QpAllocator<NV: Dim, NC: Dim>:
    Allocator<NV, NV> + Allocator<NV, NC> + Allocator<NV> + Allocator<NC> + Allocator<NC, NC>
{
}

impl<NV: Dim, NC: Dim, A> QpAllocator<NV, NC> for A where
    A: Allocator<NV, NV> + Allocator<NV, NC> + Allocator<NV> + Allocator<NC> + Allocator<NC, NC>
{
}

/// What one solve did. `Copy`, so it can travel in every cycle's diagnostics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QpStatus {
    /// All rows hold to the primal tolerance and all multipliers are >= 0: `x` is the
    /// unique minimiser.
    Solved,
    /// The constraint set is empty (certified by the dual method, see module docs).
    Infeasible,
    /// The iteration budget ran out before optimality; `x` is the last iterate
    /// (dual feasible, primal infeasible).
    IterationLimit,
    /// A non-finite number appeared in the data or the iterates, or the Hessian
    /// was not positive definite.
    NumericalError,
}

impl QpStatus {
    /// True for [`QpStatus::Solved`].
    pub fn is_solved(self) -> bool {
        matches!(self, QpStatus::Solved)
    }
    /// True for [`QpStatus::Infeasible`].
    pub fn is_infeasible(self) -> bool {
        matches!(self, QpStatus::Infeasible)
    }
}

/// Error from [`DualActiveSetOf::new`]: the Hessian cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HessianError {
    /// An entry of `H` is NaN or infinite.
    NotFinite,
    /// `H` is not symmetric to a relative 1e-12.
    NotSymmetric,
    /// The Cholesky factorisation failed: `H` is not positive definite.
    NotPositiveDefinite,
    /// `H` has no rows (`NV = 0`) or more than `u16::MAX` (only possible with
    /// run-time sizes; the static sizes are checked at compile time).
    BadSize,
}

impl core::fmt::Display for HessianError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            HessianError::NotFinite => f.write_str("Hessian has a non-finite entry"),
            HessianError::NotSymmetric => f.write_str("Hessian is not symmetric"),
            HessianError::NotPositiveDefinite => f.write_str("Hessian is not positive definite"),
            HessianError::BadSize => f.write_str("Hessian has size 0 or above 65535"),
        }
    }
}

impl core::error::Error for HessianError {}

/// Tolerances of the solver. All are absolute, applied to rows scaled to unit norm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QpSettings {
    /// A row counts as violated when `(h_i - g_i x) / |g_i| < -tol_primal`.
    pub tol_primal: f64,
    /// Relative size below which the component of a new normal outside the span of
    /// the active normals is taken as zero (linear dependence).
    pub tol_dependence: f64,
}

impl Default for QpSettings {
    fn default() -> Self {
        QpSettings {
            tol_primal: 1e-10,
            tol_dependence: 1e-12,
        }
    }
}

/// Result of one solve, for any dimension types (see [`QpSolution`] for the
/// static sizes). `lambda` holds one multiplier per row (zero for inactive
/// rows), so `H x + q + G' lambda = 0` at a solution.
#[derive(Clone, Debug)]
pub struct QpSolutionOf<NV: Dim, NC: Dim>
where
    DefaultAllocator: Allocator<NV> + Allocator<NC>,
{
    /// Primal solution (or last iterate when not solved).
    pub x: OVector<f64, NV>,
    /// Lagrange multipliers, one per row, in the order of the rows of `G`.
    /// When the status is [`QpStatus::Infeasible`] it holds instead a Farkas
    /// certificate of infeasibility: `y >= 0` with `G'y = 0` and `h'y < 0` (up
    /// to rounding), scaled so that the entry of the row that could not be
    /// added is 1.
    pub lambda: OVector<f64, NC>,
    /// Objective `1/2 x'Hx + q'x` at `x`.
    pub objective: f64,
    /// Outcome.
    pub status: QpStatus,
    /// Adds plus drops performed.
    pub iterations: u32,
    /// Indices of the active rows (first `n_active` entries valid).
    pub active: OVector<u16, NV>,
    /// Number of active rows.
    pub n_active: usize,
}

/// [`QpSolutionOf`] with the sizes as constants (stack only, `Copy`).
pub type QpSolution<const NV: usize, const NC: usize> = QpSolutionOf<Const<NV>, Const<NC>>;

impl<const NV: usize, const NC: usize> Copy for QpSolutionOf<Const<NV>, Const<NC>> {}

impl<NV: Dim, NC: Dim> QpSolutionOf<NV, NC>
where
    DefaultAllocator: Allocator<NV> + Allocator<NC>,
{
    /// The active rows as a slice.
    pub fn active_set(&self) -> &[u16] {
        let a = self.active.as_slice();
        a.get(..self.n_active.min(a.len())).unwrap_or(&[])
    }

    /// All zero, status [`QpStatus::NumericalError`].
    fn zeros_generic(nv: NV, nc: NC) -> Self {
        QpSolutionOf {
            x: OVector::zeros_generic(nv, U1),
            lambda: OVector::zeros_generic(nc, U1),
            objective: 0.0,
            status: QpStatus::NumericalError,
            iterations: 0,
            active: OVector::from_element_generic(nv, U1, 0),
            n_active: 0,
        }
    }
}

/// A QP of the form solved here, stored with a capacity of `NC` rows of which
/// the first `m` are used, for any dimension types (see [`DenseQp`] for the
/// static sizes). `gt` holds `G` transposed (one constraint normal per column)
/// so each row of `G` is contiguous.
#[derive(Clone, Debug)]
pub struct DenseQpOf<NV: Dim, NC: Dim>
where
    DefaultAllocator: Allocator<NV> + Allocator<NC> + Allocator<NV, NC>,
{
    /// Linear cost term `q`.
    pub q: OVector<f64, NV>,
    /// `G` transposed: column `i` is row `i` of `G`.
    pub gt: OMatrix<f64, NV, NC>,
    /// Right-hand side `h`.
    pub h: OVector<f64, NC>,
    /// Number of rows in use.
    pub m: usize,
}

/// [`DenseQpOf`] with the sizes as constants (stack only).
pub type DenseQp<const NV: usize, const NC: usize> = DenseQpOf<Const<NV>, Const<NC>>;

impl<const NV: usize, const NC: usize> Default for DenseQpOf<Const<NV>, Const<NC>> {
    fn default() -> Self {
        DenseQpOf {
            q: SVector::zeros(),
            gt: SMatrix::zeros(),
            h: SVector::zeros(),
            m: 0,
        }
    }
}

impl<const NV: usize, const NC: usize> DenseQpOf<Const<NV>, Const<NC>> {
    /// An empty QP (no rows, `q = 0`), all storage zero: usable in `const` and
    /// `static` initialisers (a `static` holding it lands in `.bss`).
    pub const EMPTY: Self = DenseQpOf {
        q: SVector::from_array_storage(ArrayStorage([[0.0; NV]; 1])),
        gt: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NC])),
        h: SVector::from_array_storage(ArrayStorage([[0.0; NC]; 1])),
        m: 0,
    };

    /// An empty QP with linear term `q`.
    pub fn with_q(q: SVector<f64, NV>) -> Self {
        DenseQpOf {
            q,
            ..DenseQpOf::default()
        }
    }
}

impl<NV: Dim, NC: Dim> DenseQpOf<NV, NC>
where
    DefaultAllocator: Allocator<NV> + Allocator<NC> + Allocator<NV, NC>,
{
    /// An empty QP with linear term `q` and room for `nc` rows (all zero).
    pub fn with_capacity(q: OVector<f64, NV>, nc: NC) -> Self {
        let nv = q.shape_generic().0;
        DenseQpOf {
            q,
            gt: OMatrix::zeros_generic(nv, nc),
            h: OVector::zeros_generic(nc, U1),
            m: 0,
        }
    }

    /// Removes all rows and zeroes `q`.
    pub fn clear(&mut self) {
        self.q.fill(0.0);
        self.m = 0;
    }

    /// Appends the row `g' x <= h`. Returns `Err(())` (and changes nothing) when the
    /// capacity `NC` is full.
    #[allow(clippy::result_unit_err)]
    pub fn push_row(&mut self, g: &OVector<f64, NV>, h: f64) -> Result<(), ()> {
        let nv = self.gt.nrows();
        // `gt` is column-major: column `m` of `gt` is row `m` of `G`.
        let (Some(col), Some(rhs)) = (
            column_mut(self.gt.as_mut_slice(), nv, self.m),
            self.h.as_mut_slice().get_mut(self.m),
        ) else {
            return Err(());
        };
        for (c, &v) in col.iter_mut().zip(g.as_slice()) {
            *c = v;
        }
        *rhs = h;
        self.m += 1;
        Ok(())
    }

    /// Row `i` of `G` (a column of `gt`).
    ///
    /// # Panics
    ///
    /// If `i >= NC`; see [`DenseQpOf::get_row`] for the non-panicking form.
    pub fn row(&self, i: usize) -> OVector<f64, NV> {
        self.gt.column(i).into_owned()
    }

    /// Row `i` as `(g_i, h_i)`, or `None` when `i >= NC` (rows `m..NC` are unused
    /// but exist).
    pub fn get_row(&self, i: usize) -> Option<(OVector<f64, NV>, f64)> {
        let h = *self.h.as_slice().get(i)?;
        let g = column(self.gt.as_slice(), self.gt.nrows(), i)?;
        Some((self.owned_row(g), h))
    }

    /// A row of `G` (a column of `gt`) as a vector (no allocation for static
    /// sizes, no panic: entries copied pairwise).
    fn owned_row(&self, g: &[f64]) -> OVector<f64, NV> {
        let mut v = OVector::zeros_generic(self.q.shape_generic().0, U1);
        for (a, &b) in v.iter_mut().zip(g) {
            *a = b;
        }
        v
    }

    /// The rows in use, `(g_i, h_i)` for `i = 0..m`, in order.
    pub fn rows(&self) -> impl Iterator<Item = (OVector<f64, NV>, f64)> + '_ {
        let m = self.m.min(self.gt.ncols());
        columns(self.gt.as_slice(), self.gt.nrows())
            .zip(self.h.iter())
            .take(m)
            .map(|(g, h)| (self.owned_row(g), *h))
    }

    /// The used rows with their Euclidean norms: `(g_i, h_i, |g_i|)`.
    pub fn rows_with_norm(&self) -> impl Iterator<Item = (OVector<f64, NV>, f64, f64)> + '_ {
        self.rows().map(|(g, h)| {
            let n = g.norm();
            (g, h, n)
        })
    }

    /// Largest violation `max_i (g_i x - h_i)^+` over the used rows, unscaled.
    pub fn max_violation(&self, x: &OVector<f64, NV>) -> f64 {
        let mut worst: f64 = 0.0;
        for (g, h) in self.rows() {
            let v = g.dot(x) - h;
            if v > worst {
                worst = v;
            }
        }
        worst
    }
}

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
        let nv = qp.gt.nrows();
        let m = qp.m.min(qp.gt.ncols()).min(qp.h.len());
        let mut rows = RowNormsOf {
            norm2: OVector::zeros_generic(nc, U1),
            inv_hnorm: OVector::zeros_generic(nc, U1),
            m,
            finite: true,
        };
        for (g, n2) in columns(qp.gt.as_slice(), nv)
            .zip(rows.norm2.as_mut_slice())
            .take(m)
        {
            *n2 = dot(g, g);
            // A NaN or infinite entry makes `n2` non-finite, and so does a row
            // whose squared norm overflows (|g| > ~1e154): both are numerical
            // errors.
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
    DefaultAllocator: Allocator<NV, NV> + Allocator<NV>,
{
    H: OMatrix<f64, NV, NV>,
    /// `L^-1` with `H = L L'`: lower triangular, entries above the diagonal
    /// exactly zero. Its transpose `J0 = L^-T` starts `J` in every solve.
    Linv: OMatrix<f64, NV, NV>,
    /// `L^-1` (so `H`) is diagonal: products with `L^-1` and `L^-T` cost `NV`
    /// instead of `NV^2`.
    linv_diag: bool,
    /// The diagonal of `L^-1` (for the products when `linv_diag`).
    linv_d: OVector<f64, NV>,
    settings: QpSettings,
    /// The row capacity is a parameter of the QPs solved, not of the solver's
    /// data.
    _nc: PhantomData<NC>,
}

/// [`DualActiveSetOf`] with the sizes as constants (stack only, `no_std`): the
/// controller's solver.
pub type DualActiveSet<const NV: usize, const NC: usize> = DualActiveSetOf<Const<NV>, Const<NC>>;

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
        linv_d: SVector::from_array_storage(ArrayStorage([[0.0; NV]; 1])),
        settings: QpSettings {
            tol_primal: 0.0,
            tol_dependence: 0.0,
        },
        _nc: PhantomData,
    };
}

/// Column `j` of a column-major matrix with `n` rows stored in `s`.
#[inline(always)]
pub(crate) fn column(s: &[f64], n: usize, j: usize) -> Option<&[f64]> {
    // `start..start + n`: the length is visibly `n` (a constant for the
    // static sizes), so loops over the column unroll.
    let start = j.checked_mul(n)?;
    s.get(start..start.checked_add(n)?)
}

/// Column `j` of a column-major matrix with `n` rows stored in `s`, mutable.
#[inline(always)]
pub(crate) fn column_mut(s: &mut [f64], n: usize, j: usize) -> Option<&mut [f64]> {
    let start = j.checked_mul(n)?;
    s.get_mut(start..start.checked_add(n)?)
}

/// The columns of a column-major matrix with `n > 0` rows stored in `s`
/// (nothing for `n = 0`).
#[inline(always)]
pub(crate) fn columns(s: &[f64], n: usize) -> core::slice::ChunksExact<'_, f64> {
    // `n.max(1)`: a zero chunk size would panic; with n = 0 the slice is empty.
    s.chunks_exact(n.max(1))
}

/// [`columns`], mutable.
#[inline(always)]
pub(crate) fn columns_mut(s: &mut [f64], n: usize) -> core::slice::ChunksExactMut<'_, f64> {
    s.chunks_exact_mut(n.max(1))
}

impl<NV: Dim, NC: Dim> DualActiveSetOf<NV, NC>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    /// Factors `H` (symmetric positive definite) once.
    pub fn new(H: &OMatrix<f64, NV, NV>, settings: QpSettings) -> Result<Self, HessianError> {
        let n = H.nrows();
        if n == 0 || n > usize::from(u16::MAX) {
            return Err(HessianError::BadSize);
        }
        if H.iter().any(|v| !v.is_finite()) {
            return Err(HessianError::NotFinite);
        }
        let scale = H.amax().max(f64::MIN_POSITIVE);
        // |H_ij - H_ji| for i > j; column `j` holds H_ij at `i`
        // (column-major), read with checked access (bounds the optimiser
        // could not prove for every NV, see nopanic/).
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
        let chol =
            nalgebra::linalg::Cholesky::new(H.clone()).ok_or(HessianError::NotPositiveDefinite)?;
        let L = chol.l();
        let (r, c) = H.shape_generic();
        let mut J0 = OMatrix::<f64, NV, NV>::identity_generic(r, c);
        if !L.transpose().solve_upper_triangular_mut(&mut J0) || J0.iter().any(|v| !v.is_finite()) {
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
        let linv_d = Linv.diagonal();
        Ok(DualActiveSetOf {
            H: H.clone(),
            Linv,
            linv_diag,
            linv_d,
            settings,
            _nc: PhantomData,
        })
    }

    /// The Hessian this solver was built for.
    pub fn hessian(&self) -> &OMatrix<f64, NV, NV> {
        &self.H
    }

    /// The settings.
    pub fn settings(&self) -> &QpSettings {
        &self.settings
    }

    /// Number of variables.
    pub fn nv(&self) -> usize {
        self.H.nrows()
    }

    /// Objective `1/2 x'Hx + q'x`.
    pub fn objective(&self, q: &OVector<f64, NV>, x: &OVector<f64, NV>) -> f64 {
        let mut xhx = 0.0;
        let xs = x.as_slice();
        for (col, xj) in columns(self.H.as_slice(), self.H.nrows()).zip(xs) {
            xhx += xj * dot(col, xs);
        }
        0.5 * xhx + dot(q.as_slice(), xs)
    }

    /// `w = L^-1 g` (`= J0' g`) as column axpys (no reductions);
    /// `NV` products when `H` is diagonal. `w` must be zero on entry.
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub(crate) fn linv_mul_into(&self, g: &[f64], w: &mut [f64]) {
        let n = self.H.nrows();
        if self.linv_diag {
            for ((wk, &c), &gk) in w.iter_mut().zip(self.linv_d.as_slice()).zip(g) {
                *wk = c * gk;
            }
            return;
        }
        for (col, &gk) in columns(self.Linv.as_slice(), n).zip(g) {
            // zeros above the diagonal included: fixed length, vectorised
            for (wi, c) in w.iter_mut().zip(col) {
                *wi += c * gk;
            }
        }
    }

    /// `L^-1 g` as a new vector.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub(crate) fn linv_mul(&self, g: &[f64]) -> OVector<f64, NV> {
        let mut w = OVector::zeros_generic(self.H.shape_generic().0, U1);
        self.linv_mul_into(g, w.as_mut_slice());
        w
    }

    /// `x = L^-T w` (`= J0 w`); `NV` products when `H` is diagonal.
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub(crate) fn linvt_mul(&self, w: &[f64]) -> OVector<f64, NV> {
        let n = self.H.nrows();
        let mut x = OVector::zeros_generic(self.H.shape_generic().0, U1);
        let xs = x.as_mut_slice();
        if self.linv_diag {
            for ((xk, &c), &wk) in xs.iter_mut().zip(self.linv_d.as_slice()).zip(w) {
                *xk = c * wk;
            }
            return x;
        }
        for (xk, col) in xs.iter_mut().zip(columns(self.Linv.as_slice(), n)) {
            *xk = dot(col, w); // zeros above the diagonal included: no branches
        }
        x
    }

    /// Solves the QP `qp` with at most `max_iter` adds plus drops. `prefer[i]` marks
    /// row `i` as expected active (warm start); pass all `false` (or an empty
    /// slice) for a cold start.
    pub fn solve(
        &self,
        qp: &DenseQpOf<NV, NC>,
        prefer: &[bool],
        max_iter: u32,
    ) -> QpSolutionOf<NV, NC> {
        // The H^-1 norms are left to the solve, which computes them only for
        // rows found violated.
        let mut rows = RowNormsOf::euclidean(qp);
        self.solve_with(qp, qp.h.as_slice(), None, &mut rows, prefer, max_iter)
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
    /// (else [`QpStatus::NumericalError`]).
    pub fn solve_selected(
        &self,
        qp: &DenseQpOf<NV, NC>,
        h: &OVector<f64, NC>,
        enabled: &[bool],
        prefer: &[bool],
        max_iter: u32,
    ) -> QpSolutionOf<NV, NC> {
        let mut rows = RowNormsOf::euclidean(qp);
        self.solve_with(qp, h.as_slice(), Some(enabled), &mut rows, prefer, max_iter)
    }

    /// The per-row data of `qp`'s constraint matrix that [`DualActiveSetOf::solve`]
    /// otherwise computes in every call (`m` Euclidean and `m` H^-1 row norms):
    /// prepare it once when `G` stays the same over many solves (only `q` and `h`
    /// change, as in a linear MPC with fixed constraints) and pass it to
    /// [`DualActiveSetOf::solve_prepared`].
    pub fn prepare_rows(&self, qp: &DenseQpOf<NV, NC>) -> RowNormsOf<NC> {
        let mut rows = RowNormsOf::euclidean(qp);
        let nv = qp.gt.nrows();
        for ((g, &n2), inv_hn) in columns(qp.gt.as_slice(), nv)
            .zip(rows.norm2.as_slice())
            .zip(rows.inv_hnorm.as_mut_slice())
            .take(rows.m)
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
        max_iter: u32,
    ) -> QpSolutionOf<NV, NC> {
        let mut rows = rows.clone();
        if rows.m != qp.m.min(qp.gt.ncols()).min(qp.h.len()) {
            rows.finite = false;
        }
        self.solve_with(qp, qp.h.as_slice(), None, &mut rows, prefer, max_iter)
    }

    /// `1 / |L^-1 g|` for a row with `|g|^2 = n2 > 0`.
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    fn inv_hnorm(&self, g: &[f64], n2: f64) -> f64 {
        let w = self.linv_mul(g);
        let hn = crate::float::sqrt(dot(w.as_slice(), w.as_slice()));
        // L^-1 is nonsingular, so hn > 0 for a non-zero row (barring underflow,
        // where the Euclidean norm stands in).
        if hn > 0.0 {
            1.0 / hn
        } else {
            1.0 / crate::float::sqrt(n2)
        }
    }

    /// The solve proper, with the right-hand side `h` (`qp.h` or another), the
    /// rows `!enabled[i]` left out (all in when `None`), the Euclidean row norms
    /// in `rows` and the H^-1 norms there or computed on demand (0 = not yet).
    fn solve_with(
        &self,
        qp: &DenseQpOf<NV, NC>,
        h: &[f64],
        enabled: Option<&[bool]>,
        norms: &mut RowNormsOf<NC>,
        prefer: &[bool],
        max_iter: u32,
    ) -> QpSolutionOf<NV, NC> {
        let nv = self.H.shape_generic().0;
        let n = nv.value();
        let nc = qp.h.shape_generic().0;
        let m = qp.m.min(qp.gt.ncols()).min(qp.h.len());
        let mut sol = QpSolutionOf::zeros_generic(nv, nc);
        let rows = qp.gt.as_slice(); // column `i` is row `i` of `G`
        let q = qp.q.as_slice();
        let excluded = |i: usize| enabled.is_some_and(|e| !e.get(i).copied().unwrap_or(false));
        if !norms.finite
            || qp.gt.nrows() != n
            || q.len() != n
            || m > usize::from(u16::MAX)
            || h.len() < m
            || norms.norm2.len() < m
            || !q.iter().all(|v| v.is_finite())
            || !h
                .iter()
                .enumerate()
                .take(m)
                .all(|(i, v)| excluded(i) || v.is_finite())
        {
            return sol;
        }
        let tol = self.settings.tol_primal;
        // Row norms: Euclidean for the scale-free violation test, and in the
        // metric of H^-1 (|J0' g_i| = |L^-1 g_i|) for choosing which row to add:
        // `s_i / |L^-1 g_i|` is the square root of the cost increase of enforcing
        // row i alone, which picks rows that matter and roughly halves the
        // add/drop count on the controller's QPs compared with the Euclidean rule.
        // A row is violated when `slack / |g| < -tol`, tested without the square
        // root as `slack < 0` and `slack^2 > tol^2 |g|^2`.
        let tol2 = tol * tol;
        let norm2 = norms.norm2.as_slice();
        let inv_hnorm = norms.inv_hnorm.as_mut_slice();
        let zero_infeasible = h
            .iter()
            .zip(norm2.iter())
            .enumerate()
            .take(m)
            .position(|(i, (&hi, &n2))| !excluded(i) && n2 <= ZERO_ROW2 && hi < -tol);
        if let Some(i) = zero_infeasible {
            // 0'x <= h with h < 0: nothing satisfies it; y = e_i certifies it.
            sol.status = QpStatus::Infeasible;
            if let Some(y) = sol.lambda.as_mut_slice().get_mut(i) {
                *y = 1.0;
            }
            return sol;
        }

        // Unconstrained minimiser x = -J0 J0' q = -L^-T L^-1 q.
        let v = self.linv_mul(q);
        let mut x = self.linvt_mul(v.as_slice());
        for xk in x.iter_mut() {
            *xk = -*xk;
        }
        let x = x.as_mut_slice();
        // Rows left out are never scanned: they start (and stay) marked as if
        // active, but never enter `act`.
        let mut is_active = OVector::<bool, NC>::from_element_generic(nc, U1, false);
        if enabled.is_some() {
            for (i, a) in is_active.iter_mut().enumerate() {
                *a = excluded(i);
            }
        }
        let is_active = is_active.as_mut_slice();

        let mut u = OVector::<f64, NV>::zeros_generic(nv, U1); // multipliers of the active rows
        let mut act = OVector::<u16, NV>::from_element_generic(nv, U1, 0);
        let mut r = OVector::<f64, NV>::zeros_generic(nv, U1);
        let (u, act, r) = (u.as_mut_slice(), act.as_mut_slice(), r.as_mut_slice());
        let mut nact: usize = 0;
        let mut iters: u32 = 0;
        // On infeasibility: the row `p` whose `-r` (in `r`) certifies it.
        let mut farkas: Option<usize> = None;

        // The first pass of step 1 runs at the unconstrained minimiser: when
        // no row is violated there (the cheap case) the solve ends after that
        // one pass over the rows, with no add or drop.
        let mut J = self.Linv.transpose();
        let mut R = OMatrix::<f64, NV, NV>::zeros_generic(nv, nv);
        // Work vectors of length NV.
        let mut d = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut z = OVector::<f64, NV>::zeros_generic(nv, U1);
        let mut hh = OVector::<f64, NV>::zeros_generic(nv, U1); // Householder work
        let (Js, Rs, d, z, hh) = (
            J.as_mut_slice(),
            R.as_mut_slice(),
            d.as_mut_slice(),
            z.as_mut_slice(),
            hh.as_mut_slice(),
        );
        let status = {
            {
                'outer: loop {
                    // Step 1: choose a violated row (marked rows first).
                    let p = match self
                        .select_row(rows, n, m, h, norm2, inv_hnorm, is_active, prefer, x, tol2)
                    {
                        Err(()) => break QpStatus::NumericalError,
                        Ok(None) => break QpStatus::Solved,
                        Ok(Some(p)) => p,
                    };
                    // `p < m <= NC`, so the row exists.
                    let (Some(gp), Some(&hp)) = (column(rows, n, p), h.get(p)) else {
                        break QpStatus::NumericalError;
                    };
                    let mut u_new: f64 = 0.0; // multiplier of p

                    // Step 2: move until p is satisfied (full step) or a row must be dropped.
                    loop {
                        if iters >= max_iter {
                            break 'outer QpStatus::IterationLimit;
                        }
                        // Invariant: nact <= NV (a row is only added when `add_row` found
                        // room); the `min` states it for the compiler.
                        let nact_c = nact.min(n);
                        // d = J' n_p with the GI normal n_p = -g_p (n_p'x >= -h_p).
                        for (dj, col) in d.iter_mut().zip(columns(Js, n)) {
                            *dj = -dot(col, gp);
                        }
                        // z = J2 d2: component of the step outside the active span.
                        z.fill(0.0);
                        let mut d2sq = 0.0;
                        for (col, &dj) in columns(Js, n).zip(d.iter()).skip(nact_c) {
                            for (zk, c) in z.iter_mut().zip(col) {
                                *zk += c * dj; // column j of J, j >= nact
                            }
                            d2sq += dj * dj;
                        }
                        // r = R^-1 d1 (back substitution on the active block).
                        r.fill(0.0);
                        for i in (0..nact_c).rev() {
                            let mut acc = d.get(i).copied().unwrap_or(0.0);
                            for k in (i + 1)..nact_c {
                                let rik = Rs.get(k * n + i).copied().unwrap_or(0.0);
                                acc -= rik * r.get(k).copied().unwrap_or(0.0);
                            }
                            let rii = Rs.get(i * n + i).copied().unwrap_or(0.0);
                            if let Some(ri) = r.get_mut(i) {
                                *ri = acc / rii;
                            }
                        }
                        // Partial (dual) step length t1 and the row to drop.
                        let mut t1 = f64::INFINITY;
                        let mut drop: Option<usize> = None;
                        let ra = r.get(..nact_c).unwrap_or(&[]);
                        let rmax = ra.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                        for (i, (&ri, &ui)) in ra.iter().zip(u.iter()).enumerate() {
                            if ri > 1e-14 * rmax.max(1.0) {
                                let t = ui / ri;
                                if t < t1 {
                                    t1 = t;
                                    drop = Some(i);
                                }
                            }
                        }
                        // Full (primal) step length t2.
                        let dn = crate::float::sqrt(dot(d, d));
                        let dependent =
                            crate::float::sqrt(d2sq) <= self.settings.tol_dependence * dn;
                        let slack_p = hp - dot(gp, x); // < 0 while violated
                        let t2 = if dependent {
                            f64::INFINITY
                        } else {
                            -slack_p / d2sq
                        };
                        if !(t1.is_finite() || t2.is_finite()) {
                            if t1.is_nan() || t2.is_nan() {
                                break 'outer QpStatus::NumericalError;
                            }
                            // g_p = sum_j r_j g_act[j] with every r_j <= 0 (no row can be
                            // dropped), and the active rows hold with equality while row
                            // p is violated: y_p = 1, y_act[j] = -r_j is a Farkas
                            // certificate (G'y = 0, h'y = h_p - g_p'x < 0).
                            farkas = Some(p);
                            break 'outer QpStatus::Infeasible;
                        }
                        let t = t1.min(t2);
                        iters += 1;
                        // Multipliers move along (-r, 1).
                        for (ui, &ri) in u.iter_mut().zip(r.iter()).take(nact_c) {
                            *ui -= t * ri;
                        }
                        u_new += t;
                        if !dependent {
                            for (xk, zk) in x.iter_mut().zip(z.iter()) {
                                *xk += t * zk;
                            }
                        }
                        if t2 <= t1 {
                            // Full step: p becomes active.
                            // `add_row` fails when the active set is full (nact == NV).
                            if !add_row(Js, Rs, nv, nact_c, d, hh) {
                                break 'outer QpStatus::NumericalError;
                            }
                            let (Some(a), Some(un), Some(flag)) =
                                (act.get_mut(nact_c), u.get_mut(nact_c), is_active.get_mut(p))
                            else {
                                break 'outer QpStatus::NumericalError;
                            };
                            *a = p as u16;
                            *un = u_new;
                            *flag = true;
                            nact = nact_c + 1;
                            continue 'outer;
                        }
                        // Partial step: drop row `l` (< nact), then retry the same p.
                        let Some((l, &row_l)) = drop.and_then(|l| Some((l, act.get(l)?))) else {
                            break 'outer QpStatus::NumericalError;
                        };
                        if let Some(flag) = is_active.get_mut(usize::from(row_l)) {
                            *flag = false;
                        }
                        drop_row(Js, Rs, nv, nact_c, l);
                        // Close the gap at `l` in the active list and its multipliers.
                        let last = nact_c.saturating_sub(1);
                        shift_down(act, l, last);
                        shift_down(u, l, last);
                        nact = last;
                    }
                }
            }
        };

        copy_into(sol.x.as_mut_slice(), x);
        let nact = nact.min(n);
        // Multipliers of the active rows, or the Farkas certificate.
        let lambda = sol.lambda.as_mut_slice();
        let weights: &[f64] = match farkas {
            Some(p) => {
                if let Some(y) = lambda.get_mut(p) {
                    *y = 1.0;
                }
                for y in r.iter_mut() {
                    *y = -*y;
                }
                r
            }
            None => u,
        };
        for (&row, &w) in act.iter().zip(weights.iter()).take(nact) {
            if let Some(l) = lambda.get_mut(usize::from(row)) {
                *l = w.max(0.0); // row < m <= NC: always there
            }
        }
        copy_into(sol.active.as_mut_slice(), act);
        sol.n_active = nact;
        sol.iterations = iters;
        sol.objective = self.objective(&qp.q, &sol.x);
        sol.status = if x.iter().all(|v| v.is_finite()) && sol.objective.is_finite() {
            status
        } else {
            QpStatus::NumericalError
        };
        sol
    }

    /// Step 1 of the dual method: the violated row to add (most negative
    /// slack in the metric of `H^-1`, marked rows first), `None` when every
    /// row holds to tolerance, `Err` on a non-finite slack. Computes the
    /// `H^-1` norms of the violated rows that lack one.
    #[allow(clippy::too_many_arguments)]
    #[cfg_attr(not(target_os = "none"), inline(always))]
    fn select_row(
        &self,
        rows: &[f64],
        n: usize,
        m: usize,
        h: &[f64],
        norm2: &[f64],
        inv_hnorm: &mut [f64],
        is_active: &[bool],
        prefer: &[bool],
        x: &[f64],
        tol2: f64,
    ) -> Result<Option<usize>, ()> {
        let mut best: Option<usize> = None;
        let mut best_v = 0.0;
        let mut best_pref: Option<usize> = None;
        let mut best_pref_v = 0.0;
        // Plain indices below a bound every slice visibly meets (no
        // bounds checks, no iterator adaptors in the hottest loop).
        let m = m
            .min(norm2.len())
            .min(inv_hnorm.len())
            .min(h.len())
            .min(is_active.len());
        let (norm2, inv_hnorm, h, is_active) =
            (&norm2[..m], &mut inv_hnorm[..m], &h[..m], &is_active[..m]);
        let mut cols = columns(rows, n);
        for i in 0..m {
            // Row `i` of `G` (the iterator keeps pace with `i`).
            let Some(g) = cols.next() else {
                break;
            };
            let n2 = norm2[i];
            if is_active[i] || n2 <= ZERO_ROW2 {
                continue;
            }
            let slack = h[i] - dot(g, x);
            if !slack.is_finite() {
                return Err(());
            }
            if slack >= 0.0 || slack * slack <= tol2 * n2 {
                continue; // satisfied to tolerance
            }
            if inv_hnorm[i] == 0.0 {
                inv_hnorm[i] = self.inv_hnorm(g, n2);
            }
            let s = slack * inv_hnorm[i];
            if s < best_v {
                best_v = s;
                best = Some(i);
            }
            if prefer.get(i).copied().unwrap_or(false) && s < best_pref_v {
                best_pref_v = s;
                best_pref = Some(i);
            }
        }
        Ok(best_pref.or(best))
    }
}

/// Adds a row whose `d = J' n` is given: one Householder reflection of
/// columns `nact..NV` of `J` (`n x n`, column-major in `Js`) maps `d[nact..]`
/// to `alpha e_nact` (`|alpha| = |d[nact..]|`), and `d[..nact], alpha` becomes
/// column `nact` of `R`. Half the flops of the equivalent Givens sweep, and all
/// of them vectorise. `w` is work space of length `n`; `d` is overwritten.
#[inline]
fn add_row<NV: Dim>(
    Js: &mut [f64],
    Rs: &mut [f64],
    nv: NV,
    nact: usize,
    d: &mut [f64],
    w: &mut [f64],
) -> bool {
    let n = nv.value();
    if nact >= n {
        return false;
    }
    let Some(&d0) = d.get(nact) else {
        return false;
    };
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
        // v = d with v[nact] = d0 - alpha (only entries nact.. are used).
        if let Some(v0) = d.get_mut(nact) {
            *v0 = d0 - alpha;
        }
        let beta = 1.0 / (norm * (norm + d0.abs()));
        // J2 <- J2 (I - beta v v'): w = J2 v, then column j -= beta v_j w.
        w.fill(0.0);
        for (col, &vj) in columns(Js, n).zip(d.iter()).skip(nact) {
            for (wk, c) in w.iter_mut().zip(col) {
                *wk += c * vj;
            }
        }
        for (col, &vj) in columns_mut(Js, n).zip(d.iter()).skip(nact) {
            let f = beta * vj;
            for (c, wk) in col.iter_mut().zip(w.iter()) {
                *c -= f * wk;
            }
        }
        if let Some(v0) = d.get_mut(nact) {
            *v0 = alpha;
        }
    }
    // Column `nact` of R gets d[..=nact] (checked access, as in drop_row).
    let Some(col) = column_mut(Rs, n, nact) else {
        return false;
    };
    for (r, &di) in col.iter_mut().zip(d.iter()).take(nact + 1) {
        *r = di;
    }
    col.get(nact).is_some_and(|&r| r != 0.0 && r.is_finite())
}

/// Removes active row `l` (of `nact`): deletes column `l` of `R` (`n x n`,
/// column-major in `Rs`) and restores the triangle with Givens rotations,
/// applied to `J` (in `Js`) as well.
#[inline]
fn drop_row<NV: Dim>(Js: &mut [f64], Rs: &mut [f64], nv: NV, nact: usize, l: usize) {
    let n = nv.value();
    let nact = nact.min(n); // invariant of `solve`, stated for the compiler
    // Columns l+1..nact move one to the left; column nact-1 is cleared.
    if let Some(block) = Rs.get_mut(l.saturating_mul(n)..nact.saturating_mul(n)) {
        let len = block.len();
        if len >= n {
            block.copy_within(n.., 0);
            if let Some(tail) = block.get_mut(len - n..) {
                tail.fill(0.0);
            }
        }
    }
    // Column `col` now has a sub-diagonal entry at row col+1 for col >= l.
    for col in l..nact.saturating_sub(1) {
        let Some(cc) = column_mut(Rs, n, col) else {
            break;
        };
        let (Some(&a), Some(&b)) = (cc.get(col), cc.get(col + 1)) else {
            break;
        };
        if b == 0.0 {
            continue;
        }
        let (c, s, rr) = givens(a, b);
        if let Some([ra, rb]) = cc.get_mut(col..col + 2) {
            *ra = rr;
            *rb = 0.0;
        }
        // Columns k in col+1..nact-1 (checked access: the optimiser cannot
        // prove the bounds for every NV, see nopanic/).
        for rk in columns_mut(Rs, n).take(nact - 1).skip(col + 1) {
            if let [.., ra, rb] = rk.get_mut(..col + 2).unwrap_or(&mut []) {
                let (a, b) = (*ra, *rb);
                *ra = c * a + s * b;
                *rb = -s * a + c * b;
            }
        }
        rotate_columns(Js, nv, col, c, s);
    }
}

/// Something that solves the controller's QPs. The controller uses
/// [`OwnSolver`] (the dual active-set method of this module); the reference crate
/// plugs in Clarabel through this trait so a whole closed loop can be run with
/// either solver and compared.
pub trait QpBackend<const NV: usize, const NC: usize> {
    /// Solves `min 1/2 u'Hu + q'u, G u <= h` where `H = solver.hessian()` and the
    /// rest is `qp`. `prefer` and `max_iter` are hints an external solver may ignore.
    fn solve_qp(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC>;

    /// [`QpBackend::solve_qp`] on the rows `i` of `qp` with `enabled[i]`, with the
    /// right-hand side `h` instead of `qp.h`, multipliers (and `prefer`) indexed
    /// like `qp`'s rows; see [`DualActiveSetOf::solve_selected`]. The provided
    /// method copies the enabled rows into a compact QP (on the stack) for
    /// `solve_qp` and maps the result back; [`OwnSolver`] solves in place.
    fn solve_selected(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        h: &SVector<f64, NC>,
        enabled: &[bool; NC],
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        let mut sub = DenseQp::with_q(qp.q);
        // Compact row -> row of `qp`, and the compact rows' warm-start marks.
        let mut orig = [0u16; NC];
        let mut sub_prefer = [false; NC];
        for (i, (g, &hi)) in qp.gt.data.0.iter().zip(h.iter()).enumerate().take(qp.m) {
            if !enabled.get(i).copied().unwrap_or(false) {
                continue;
            }
            let k = sub.m;
            // Capacity cannot be exceeded: a subset of `qp`'s rows.
            if sub.push_row(&SVector::from(*g), hi).is_ok()
                && let (Some(o), Some(p)) = (orig.get_mut(k), sub_prefer.get_mut(k))
            {
                *o = i as u16;
                *p = prefer.get(i).copied().unwrap_or(false);
            }
        }
        let s = self.solve_qp(solver, &sub, &sub_prefer, max_iter);
        let mut out = QpSolution {
            lambda: SVector::zeros(),
            ..s
        };
        for (&y, &o) in s.lambda.iter().zip(&orig).take(sub.m) {
            if let Some(l) = out.lambda.get_mut(usize::from(o)) {
                *l = y;
            }
        }
        for a in out.active.iter_mut().take(s.n_active) {
            *a = orig.get(usize::from(*a)).copied().unwrap_or(*a);
        }
        out
    }
}

/// The built-in backend: [`DualActiveSetOf::solve`].
#[derive(Clone, Copy, Debug, Default)]
pub struct OwnSolver;

impl<const NV: usize, const NC: usize> QpBackend<NV, NC> for OwnSolver {
    fn solve_qp(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        solver.solve(qp, prefer, max_iter)
    }

    fn solve_selected(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        h: &SVector<f64, NC>,
        enabled: &[bool; NC],
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        solver.solve_selected(qp, h, enabled, prefer, max_iter)
    }
}

/// `a . b` over the common length with two partial sums (independent add
/// chains: entry `k` goes to sum `k % 2`, the sums are added at the end). The
/// pairs are explicit so that the two sums become the two lanes of one SIMD
/// register, and for slices of a constant length the loop unrolls. Plain
/// indices below lengths the optimiser can see (no iterator adaptors to
/// inline into the large solver loops, no bounds checks left).
#[inline(always)]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 2];
    let (pa, ra) = a.as_chunks::<2>();
    let (pb, rb) = b.as_chunks::<2>();
    let k = pa.len().min(pb.len());
    let (pa, pb) = (&pa[..k], &pb[..k]);
    for i in 0..k {
        acc[0] += pa[i][0] * pb[i][0];
        acc[1] += pa[i][1] * pb[i][1];
    }
    // An odd common length leaves one entry, of even index `2 k`.
    let n = a.len().min(b.len());
    if n > 2 * k {
        let x = if pa.len() == k {
            ra.first()
        } else {
            a.get(2 * k)
        };
        let y = if pb.len() == k {
            rb.first()
        } else {
            b.get(2 * k)
        };
        if let (Some(x), Some(y)) = (x, y) {
            acc[0] += x * y;
        }
    }
    acc[0] + acc[1]
}

/// `dst[i] = src[i]` over the common length (no panic on a length
/// mismatch, unlike `copy_from_slice`).
#[inline(always)]
pub(crate) fn copy_into<T: Copy>(dst: &mut [T], src: &[T]) {
    for (d, &s) in dst.iter_mut().zip(src) {
        *d = s;
    }
}

/// `a[i] = a[i + 1]` for `i` in `l..last` (closes the gap left at `l` in the
/// first `last + 1` entries; entry `last` keeps its value).
#[inline(always)]
pub(crate) fn shift_down<T: Copy>(a: &mut [T], l: usize, last: usize) {
    for i in l..last {
        if let Some(&next) = a.get(i + 1)
            && let Some(e) = a.get_mut(i)
        {
            *e = next;
        }
    }
}

/// Givens rotation `(c, s, r)` with `c a + s b = r`, `-s a + c b = 0`.
pub(crate) fn givens(a: f64, b: f64) -> (f64, f64, f64) {
    // sqrt(a^2 + b^2) is within an ulp or two of hypot; hypot (slower, no
    // overflow or underflow) only when the squares leave the normal range.
    let r2 = a * a + b * b;
    let r = if (1e-280..=1e280).contains(&r2) {
        crate::float::sqrt(r2)
    } else {
        libm::hypot(a, b)
    };
    if r == 0.0 {
        return (1.0, 0.0, 0.0);
    }
    (a / r, b / r, r)
}

/// `[Ji, Jj] <- [c Ji + s Jj, -s Ji + c Jj]` for the adjacent columns `i` and
/// `j = i + 1` of the `n`-row column-major `Js` (the callers' only use); with
/// `j >= n` nothing happens.
#[inline]
fn rotate_columns<NV: Dim>(Js: &mut [f64], nv: NV, i: usize, c: f64, s: f64) {
    let n = nv.value();
    let Some(pair) = Js.get_mut(i.saturating_mul(n)..i.saturating_add(2).saturating_mul(n)) else {
        return;
    };
    if let Some((ji, jj)) = pair.split_at_mut_checked(n) {
        for (a, b) in ji.iter_mut().zip(jj.iter_mut()) {
            let (x, y) = (*a, *b);
            *a = c * x + s * y;
            *b = -s * x + c * y;
        }
    }
}

/// The dynamically sized solver types (feature `alloc`): sizes chosen at run
/// time, buffers on the heap, the same code as the static sizes.
#[cfg(feature = "alloc")]
mod dynamic {
    use nalgebra::Dyn;

    use super::{DenseQpOf, DualActiveSetOf, QpSolutionOf, RowNormsOf};

    /// [`DualActiveSetOf`] with run-time sizes.
    pub type DualActiveSetDyn = DualActiveSetOf<Dyn, Dyn>;
    /// [`DenseQpOf`] with run-time sizes.
    pub type DenseQpDyn = DenseQpOf<Dyn, Dyn>;
    /// [`QpSolutionOf`] with run-time sizes.
    pub type QpSolutionDyn = QpSolutionOf<Dyn, Dyn>;
    /// [`RowNormsOf`] with a run-time row count.
    pub type RowNormsDyn = RowNormsOf<Dyn>;
}

#[cfg(feature = "alloc")]
pub use dynamic::{DenseQpDyn, DualActiveSetDyn, QpSolutionDyn, RowNormsDyn};

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    fn solver2() -> DualActiveSet<2, 4> {
        DualActiveSet::new(&Matrix2::new(2.0, 0.0, 0.0, 2.0), QpSettings::default()).unwrap()
    }

    #[test]
    fn unconstrained_minimiser() {
        let s = solver2();
        let qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
        let sol = s.solve(&qp, &[false; 4], 10);
        assert_eq!(sol.status, QpStatus::Solved);
        assert!((sol.x - Vector2::new(1.0, 2.0)).amax() < 1e-14);
        assert_eq!(sol.iterations, 0);
        assert!((sol.objective - (-5.0)).abs() < 1e-14);
    }

    #[test]
    fn one_active_bound_and_multiplier() {
        // min (x-1)^2 + (y-2)^2, s.t. x + y <= 1  -> x = 0, y = 1, lambda = 2.
        let s = solver2();
        let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
        qp.push_row(&Vector2::new(1.0, 1.0), 1.0).unwrap();
        let sol = s.solve(&qp, &[false; 4], 10);
        assert_eq!(sol.status, QpStatus::Solved);
        assert!((sol.x - Vector2::new(0.0, 1.0)).amax() < 1e-14);
        assert!((sol.lambda[0] - 2.0).abs() < 1e-14);
        assert_eq!(sol.active_set(), &[0]);
    }

    #[test]
    fn drop_happens_and_result_is_optimal() {
        // min (x-1)^2 + (y-2)^2 with y <= 0 and x <= -1, x + y <= -2 (redundant-ish)
        let s = solver2();
        let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
        qp.push_row(&Vector2::new(1.0, 1.0), -2.0).unwrap();
        qp.push_row(&Vector2::new(0.0, 1.0), 0.0).unwrap();
        qp.push_row(&Vector2::new(1.0, 0.0), -1.0).unwrap();
        let sol = s.solve(&qp, &[false; 4], 20);
        assert_eq!(sol.status, QpStatus::Solved);
        // Projection of (1, 2) onto {x + y <= -2}: (-1.5, -0.5), which satisfies
        // the other two rows.
        assert!(
            (sol.x - Vector2::new(-1.5, -0.5)).amax() < 1e-12,
            "{:?}",
            sol.x
        );
        assert!(qp.max_violation(&sol.x) < 1e-12);
        let grad = s.hessian() * sol.x + qp.q;
        let mut stat = grad;
        for i in 0..qp.m {
            stat += qp.row(i) * sol.lambda[i];
            assert!(sol.lambda[i] >= 0.0);
        }
        assert!(stat.amax() < 1e-12);
    }

    /// Checks a Farkas certificate: y >= 0, |G'y| small, h'y < 0.
    fn assert_certificate<const NV: usize, const NC: usize>(
        qp: &DenseQp<NV, NC>,
        y: &SVector<f64, NC>,
    ) {
        let mut gty = SVector::<f64, NV>::zeros();
        let mut hty = 0.0;
        for i in 0..qp.m {
            assert!(y[i] >= 0.0);
            gty += qp.row(i) * y[i];
            hty += qp.h[i] * y[i];
        }
        assert!(gty.amax() <= 1e-12 * (1.0 + y.amax()), "G'y = {gty:?}");
        assert!(hty < 0.0, "h'y = {hty}");
    }

    #[test]
    fn infeasible_detected() {
        let s = solver2();
        let mut qp = DenseQp::<2, 4>::default();
        qp.push_row(&Vector2::new(1.0, 0.0), -1.0).unwrap(); // x <= -1
        qp.push_row(&Vector2::new(-1.0, 0.0), -1.0).unwrap(); // x >= 1
        let sol = s.solve(&qp, &[false; 4], 20);
        assert_eq!(sol.status, QpStatus::Infeasible);
        assert_certificate(&qp, &sol.lambda);
        // Three rows, one of them irrelevant: x + y <= -1, x >= 0, y >= 0.
        let mut qp = DenseQp::<2, 4>::default();
        qp.push_row(&Vector2::new(0.0, 1.0), 5.0).unwrap();
        qp.push_row(&Vector2::new(1.0, 1.0), -1.0).unwrap();
        qp.push_row(&Vector2::new(-1.0, 0.0), 0.0).unwrap();
        qp.push_row(&Vector2::new(0.0, -1.0), 0.0).unwrap();
        let sol = s.solve(&qp, &[false; 4], 20);
        assert_eq!(sol.status, QpStatus::Infeasible);
        assert_certificate(&qp, &sol.lambda);
        assert_eq!(sol.lambda[0], 0.0);
    }

    #[test]
    fn zero_row_negative_rhs_is_infeasible() {
        let s = solver2();
        let mut qp = DenseQp::<2, 4>::default();
        qp.push_row(&Vector2::new(0.0, 0.0), -1.0).unwrap();
        assert_eq!(s.solve(&qp, &[false; 4], 20).status, QpStatus::Infeasible);
        let mut qp = DenseQp::<2, 4>::default();
        qp.push_row(&Vector2::new(0.0, 0.0), 1.0).unwrap();
        assert_eq!(s.solve(&qp, &[false; 4], 20).status, QpStatus::Solved);
    }

    #[test]
    fn budget_is_respected() {
        let s = solver2();
        let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
        qp.push_row(&Vector2::new(1.0, 1.0), -2.0).unwrap();
        qp.push_row(&Vector2::new(0.0, 1.0), -1.0).unwrap();
        let full = s.solve(&qp, &[false; 4], 10);
        assert_eq!(full.status, QpStatus::Solved);
        assert_eq!(full.iterations, 2);
        let sol = s.solve(&qp, &[false; 4], 1);
        assert_eq!(sol.status, QpStatus::IterationLimit);
        assert_eq!(sol.iterations, 1);
        let sol = s.solve(&qp, &[false; 4], 0);
        assert_eq!(sol.status, QpStatus::IterationLimit);
        assert_eq!(sol.iterations, 0);
    }

    #[test]
    fn non_finite_data_is_numerical_error() {
        let s = solver2();
        let qp = DenseQp::<2, 4>::with_q(Vector2::new(f64::NAN, 0.0));
        assert_eq!(
            s.solve(&qp, &[false; 4], 10).status,
            QpStatus::NumericalError
        );
    }

    #[test]
    fn bad_hessians_rejected() {
        let e =
            DualActiveSet::<2, 4>::new(&Matrix2::new(1.0, 0.0, 0.0, -1.0), QpSettings::default());
        assert_eq!(e.unwrap_err(), HessianError::NotPositiveDefinite);
        let e =
            DualActiveSet::<2, 4>::new(&Matrix2::new(1.0, 0.5, 0.0, 1.0), QpSettings::default());
        assert_eq!(e.unwrap_err(), HessianError::NotSymmetric);
        // Every pair is compared: an asymmetry in any one off-diagonal pair of a
        // 6 x 6 Hessian is found, on either side of the diagonal.
        for (i, j) in [(4, 2), (2, 4), (5, 0), (0, 5), (1, 0)] {
            let mut h = SMatrix::<f64, 6, 6>::identity() * 2.0;
            h[(i, j)] = 1e-6;
            let e = DualActiveSet::<6, 4>::new(&h, QpSettings::default());
            assert_eq!(e.unwrap_err(), HessianError::NotSymmetric, "({i}, {j})");
        }
        let e = DualActiveSet::<2, 4>::new(
            &Matrix2::new(f64::NAN, 0.0, 0.0, 1.0),
            QpSettings::default(),
        );
        assert_eq!(e.unwrap_err(), HessianError::NotFinite);
    }

    #[test]
    fn prepared_rows_give_the_same_solve() {
        // A non-diagonal Hessian (dense path) and the diagonal one (fast path).
        let dense =
            DualActiveSet::<2, 4>::new(&Matrix2::new(3.0, 1.0, 1.0, 2.0), QpSettings::default())
                .unwrap();
        for s in [dense, solver2()] {
            let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
            qp.push_row(&Vector2::new(1.0, 1.0), -2.0).unwrap();
            qp.push_row(&Vector2::new(0.0, 1.0), 0.0).unwrap();
            qp.push_row(&Vector2::new(1.0, 0.0), -1.0).unwrap();
            let rows = s.prepare_rows(&qp);
            let cold = s.solve(&qp, &[false; 4], 20);
            assert_eq!(cold.status, QpStatus::Solved);
            // KKT: H x + q + G' lambda = 0, lambda >= 0, rows hold.
            let mut stat = s.hessian() * cold.x + qp.q;
            for i in 0..qp.m {
                stat += qp.row(i) * cold.lambda[i];
                assert!(cold.lambda[i] >= 0.0);
            }
            assert!(stat.amax() < 1e-12, "{stat:?}");
            assert!(qp.max_violation(&cold.x) < 1e-12);
            // Same G, other h and q: the prepared rows still apply.
            qp.h[0] = -3.0;
            qp.q = Vector2::new(1.0, -1.0);
            let a = s.solve(&qp, &[false; 4], 20);
            let b = s.solve_prepared(&qp, &rows, &[false; 4], 20);
            assert_eq!(a.status, b.status);
            assert_eq!(a.iterations, b.iterations);
            assert_eq!(a.x, b.x);
            // Rows prepared for another row count are refused.
            qp.push_row(&Vector2::new(-1.0, 0.0), 5.0).unwrap();
            let c = s.solve_prepared(&qp, &rows, &[false; 4], 20);
            assert_eq!(c.status, QpStatus::NumericalError);
        }
    }

    /// KKT conditions of a solution, or the certificate of an infeasible QP.
    fn assert_kkt<const NV: usize, const NC: usize>(
        s: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        sol: &QpSolution<NV, NC>,
    ) {
        match sol.status {
            QpStatus::Solved => {
                let mut stat = s.hessian() * sol.x + qp.q;
                for i in 0..qp.m {
                    let (g, h) = qp.get_row(i).unwrap();
                    let slack = h - g.dot(&sol.x);
                    assert!(sol.lambda[i] >= 0.0);
                    assert!(slack >= -1e-9, "row {i} violated by {slack}");
                    assert!((sol.lambda[i] * slack).abs() < 1e-9, "complementarity");
                    stat += g * sol.lambda[i];
                }
                assert!(stat.amax() < 1e-9, "stationarity {stat:?}");
            }
            QpStatus::Infeasible => assert_certificate(qp, &sol.lambda),
            other => panic!("unexpected status {other:?}"),
        }
    }

    /// Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG, top bits).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    #[test]
    fn diagonal_and_dense_hessians_satisfy_kkt_on_random_qps() {
        // Deterministic pseudo-random QPs (64-bit LCG), both Hessian code paths.
        let mut rnd = uniform(0x2545_f491_4f6c_dd1d);
        let (mut solved, mut infeasible) = (0, 0);
        for k in 0..400 {
            let H = if k % 2 == 0 {
                SMatrix::<f64, 6, 6>::from_diagonal(&SVector::from_fn(|_, _| {
                    0.1 + 10.0 * rnd().abs()
                }))
            } else {
                let A = SMatrix::<f64, 6, 6>::from_fn(|_, _| rnd());
                A.transpose() * A + SMatrix::identity() * 0.1
            };
            let s = DualActiveSet::<6, 24>::new(&H, QpSettings::default()).unwrap();
            assert_eq!(s.linv_diag, k % 2 == 0);
            let mut qp = DenseQp::<6, 24>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
            for _ in 0..(4 + k % 20) {
                let g = SVector::<f64, 6>::from_fn(|_, _| rnd());
                qp.push_row(&g, rnd() + 0.3).unwrap();
            }
            let sol = s.solve(&qp, &[false; 24], 200);
            assert_kkt(&s, &qp, &sol);
            let rows = s.prepare_rows(&qp);
            let prepared = s.solve_prepared(&qp, &rows, &[false; 24], 200);
            assert_eq!(prepared.x, sol.x);
            solved += usize::from(sol.status.is_solved());
            infeasible += usize::from(sol.status.is_infeasible());
        }
        // Both outcomes are exercised.
        assert!(
            solved > 100 && infeasible > 10,
            "{solved} solved, {infeasible} infeasible"
        );
    }

    /// `solve_selected` (in place) is bit for bit `solve` on the compacted QP,
    /// and so is the provided `QpBackend::solve_selected` (which compacts),
    /// with multipliers, active set and warm-start marks mapped between the two
    /// row numberings; a non-finite right-hand side of a left-out row is
    /// ignored.
    #[test]
    fn solve_selected_is_solve_on_the_selected_rows() {
        struct Compacting;
        impl QpBackend<6, 24> for Compacting {
            fn solve_qp(
                &mut self,
                solver: &DualActiveSet<6, 24>,
                qp: &DenseQp<6, 24>,
                prefer: &[bool; 24],
                max_iter: u32,
            ) -> QpSolution<6, 24> {
                solver.solve(qp, prefer, max_iter)
            }
        }
        let mut rnd = uniform(0x0bad_5eed_1234_5678);
        let (mut solved, mut infeasible) = (0, 0);
        for k in 0..400 {
            let H = SMatrix::<f64, 6, 6>::identity() * 2.0;
            let s = DualActiveSet::<6, 24>::new(&H, QpSettings::default()).unwrap();
            let mut qp = DenseQp::<6, 24>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
            let mut h = SVector::<f64, 24>::zeros();
            let mut enabled = [false; 24];
            let mut prefer = [false; 24];
            let mut sub = DenseQp::<6, 24>::with_q(qp.q);
            let mut sub_prefer = [false; 24];
            let mut orig = [0usize; 24];
            for i in 0..(4 + k % 20) {
                let g = SVector::<f64, 6>::from_fn(|_, _| rnd());
                qp.push_row(&g, 7.0).unwrap();
                enabled[i] = rnd() < 0.5;
                prefer[i] = rnd() < -0.6;
                h[i] = if enabled[i] { rnd() + 0.3 } else { f64::NAN };
                if enabled[i] {
                    orig[sub.m] = i;
                    sub_prefer[sub.m] = prefer[i];
                    sub.push_row(&g, h[i]).unwrap();
                }
            }
            let want = s.solve(&sub, &sub_prefer, 200);
            for got in [
                s.solve_selected(&qp, &h, &enabled, &prefer, 200),
                Compacting.solve_selected(&s, &qp, &h, &enabled, &prefer, 200),
            ] {
                assert_eq!(got.status, want.status);
                assert_eq!(got.iterations, want.iterations);
                assert_eq!(got.x.map(f64::to_bits), want.x.map(f64::to_bits));
                assert_eq!(got.objective.to_bits(), want.objective.to_bits());
                let mut lambda = SVector::<f64, 24>::zeros();
                for j in 0..sub.m {
                    lambda[orig[j]] = want.lambda[j];
                }
                assert_eq!(got.lambda.map(f64::to_bits), lambda.map(f64::to_bits));
                assert_eq!(got.n_active, want.n_active);
                for (&g, &w) in got.active_set().iter().zip(want.active_set()) {
                    assert_eq!(usize::from(g), orig[usize::from(w)]);
                }
            }
            solved += usize::from(want.status.is_solved());
            infeasible += usize::from(want.status.is_infeasible());
        }
        assert!(
            solved > 100 && infeasible > 10,
            "{solved} solved, {infeasible} infeasible"
        );
    }

    #[test]
    fn overflowing_row_norm_is_numerical_error() {
        let s = solver2();
        let mut qp = DenseQp::<2, 4>::default();
        qp.push_row(&Vector2::new(1e200, 0.0), 1.0).unwrap();
        assert_eq!(
            s.solve(&qp, &[false; 4], 10).status,
            QpStatus::NumericalError
        );
    }

    #[test]
    fn warm_start_marks_do_not_change_solution() {
        let s = solver2();
        let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
        qp.push_row(&Vector2::new(1.0, 1.0), -2.0).unwrap();
        qp.push_row(&Vector2::new(0.0, 1.0), 0.0).unwrap();
        qp.push_row(&Vector2::new(1.0, 0.0), -1.0).unwrap();
        let cold = s.solve(&qp, &[false; 4], 20);
        // Wrong guesses cost iterations but not accuracy.
        let wrong = s.solve(&qp, &[false, true, true, false], 20);
        assert_eq!(wrong.status, QpStatus::Solved);
        assert!((cold.x - wrong.x).amax() < 1e-12);
        assert!(wrong.iterations > cold.iterations);
        // The right guess is never slower.
        let right = s.solve(&qp, &[true, false, false, false], 20);
        assert!((cold.x - right.x).amax() < 1e-12);
        assert!(right.iterations <= cold.iterations);
    }

    /// The static (`Const`) and dynamic (`Dyn`) instances of the one
    /// algorithm give bit-identical results (x, multipliers, objective,
    /// status, iterations, active set) on random QPs at the controller's
    /// sizes, for `solve`, `solve_prepared`, `solve_selected` and the LDP path.
    #[cfg(feature = "alloc")]
    fn static_and_dynamic_agree_bit_for_bit<const NV: usize, const NC: usize>(seed: u64) {
        use crate::ldp::{LdpSolver, LdpSolverDyn};
        use nalgebra::{DMatrix, DVector, Dyn};
        fn same<NV: nalgebra::Dim, NC: nalgebra::Dim, MV: nalgebra::Dim, MC: nalgebra::Dim>(
            a: &QpSolutionOf<NV, NC>,
            b: &QpSolutionOf<MV, MC>,
        ) where
            DefaultAllocator: Allocator<NV> + Allocator<NC> + Allocator<MV> + Allocator<MC>,
        {
            let same_bits = |u: &[f64], v: &[f64]| {
                u.len() == v.len() && u.iter().zip(v).all(|(x, y)| x.to_bits() == y.to_bits())
            };
            assert_eq!(a.status, b.status);
            assert_eq!(a.iterations, b.iterations);
            assert!(
                same_bits(a.x.as_slice(), b.x.as_slice()),
                "{:?} {:?}",
                a.x,
                b.x
            );
            // The static capacity may exceed the dynamic row count: rows
            // beyond it are unused and carry zero multipliers.
            let (la, lb) = (a.lambda.as_slice(), b.lambda.as_slice());
            assert!(same_bits(&la[..lb.len()], lb));
            assert!(la[lb.len()..].iter().all(|&y| y == 0.0));
            assert_eq!(a.objective.to_bits(), b.objective.to_bits());
            assert_eq!(a.active_set(), b.active_set());
        }
        let mut rnd = uniform(seed);
        let mut solved = 0;
        for k in 0..60 {
            let H = if k % 2 == 0 {
                SMatrix::<f64, NV, NV>::identity() * 2.0
            } else {
                let A = SMatrix::<f64, NV, NV>::from_fn(|_, _| rnd());
                A.transpose() * A + SMatrix::identity() * 0.1
            };
            let s = DualActiveSet::<NV, NC>::new(&H, QpSettings::default()).unwrap();
            let d = DualActiveSetDyn::new(
                &DMatrix::from_column_slice(NV, NV, H.as_slice()),
                QpSettings::default(),
            )
            .unwrap();
            let mut qp = DenseQp::<NV, NC>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
            let m = 1 + k % NC;
            let mut dq =
                DenseQpDyn::with_capacity(DVector::from_column_slice(qp.q.as_slice()), Dyn(m));
            let mut enabled = [false; NC];
            let mut prefer = [false; NC];
            for i in 0..m {
                let g = SVector::<f64, NV>::from_fn(|_, _| rnd());
                let h = rnd() + 0.3;
                qp.push_row(&g, h).unwrap();
                dq.push_row(&DVector::from_column_slice(g.as_slice()), h)
                    .unwrap();
                enabled[i] = rnd() < 0.6;
                prefer[i] = rnd() < -0.6;
            }
            let a = s.solve(&qp, &prefer, 200);
            let b = d.solve(&dq, &prefer[..m], 200);
            same(&a, &b);
            solved += usize::from(a.status.is_solved());
            same(
                &s.solve_prepared(&qp, &s.prepare_rows(&qp), &prefer, 200),
                &d.solve_prepared(&dq, &d.prepare_rows(&dq), &prefer[..m], 200),
            );
            same(
                &s.solve_selected(&qp, &qp.h, &enabled, &prefer, 200),
                &d.solve_selected(&dq, &dq.h, &enabled[..m], &prefer[..m], 200),
            );
            same(
                &LdpSolver::prepare(&s, &qp).solve_qp(&qp, &prefer, 200),
                &LdpSolverDyn::prepare(&d, &dq).solve_qp(&dq, &prefer[..m], 200),
            );
        }
        assert!(solved > 10, "{solved}");
    }

    #[cfg(feature = "alloc")]
    #[test]
    fn static_and_dynamic_paths_are_bit_identical_at_the_controller_sizes() {
        // N = 3 (6 variables, 48 rows), N = 5 (10, 80), LIPMWALK (16, 32).
        static_and_dynamic_agree_bit_for_bit::<6, 48>(1);
        static_and_dynamic_agree_bit_for_bit::<10, 80>(2);
        static_and_dynamic_agree_bit_for_bit::<16, 32>(3);
    }
}
