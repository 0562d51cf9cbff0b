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
//! [`DualActiveSet::solve_prepared`]. The kernels are written over fixed-size
//! arrays (lengths are the constants `NV`, `NC`), so the compiler unrolls and
//! vectorises them without bounds checks; see `docs/solvers.md` for the
//! measurements that chose them.
//!
//! Iteration count = number of adds plus drops; it never exceeds the budget passed
//! to `solve`. Every loop is bounded by `NV`, `NC` or the budget.
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

use nalgebra::{ArrayStorage, SMatrix, SVector};

use crate::active_set::{self, dot};

mod orthogonal;
use orthogonal::Orthogonal;

/// Rows whose squared Euclidean norm is not above this (it is 0 for an exactly
/// zero row or one whose squares underflow, `|g| < ~1e-162`) are treated as zero
/// rows: satisfied when `h_i >= -tol`, infeasible otherwise.
pub(crate) const ZERO_ROW2: f64 = 0.0;

/// Smallest number of variables for which [`QpSettings::hot_start`] is
/// compiled in (the controller's horizons `N >= 8`). Below it, scanning the
/// marked rows first gets most of the gain, and the hot start's code (3.8 KiB
/// of Thumb at `NV = 6`) would not fit the firmware's 64 KiB of flash
/// (`docs/horizon.md`).
pub const HOT_START_MIN_NV: usize = 16;

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

/// Error from [`DualActiveSet::new`]: the Hessian cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HessianError {
    /// An entry of `H` is NaN or infinite.
    NotFinite,
    /// `H` is not symmetric to a relative 1e-12.
    NotSymmetric,
    /// The Cholesky factorisation failed: `H` is not positive definite.
    NotPositiveDefinite,
}

impl core::fmt::Display for HessianError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            HessianError::NotFinite => f.write_str("Hessian has a non-finite entry"),
            HessianError::NotSymmetric => f.write_str("Hessian is not symmetric"),
            HessianError::NotPositiveDefinite => f.write_str("Hessian is not positive definite"),
        }
    }
}

impl core::error::Error for HessianError {}

/// Tolerances and options of the solver. The tolerances are absolute, applied to
/// rows scaled to unit norm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QpSettings {
    /// A row counts as violated when `(h_i - g_i x) / |g_i| < -tol_primal`.
    pub tol_primal: f64,
    /// Relative size below which the component of a new normal outside the span of
    /// the active normals is taken as zero (linear dependence).
    pub tol_dependence: f64,
    /// Hot start: the rows marked in `prefer` enter the active set together
    /// before the first row scan (module docs; compiled in from
    /// [`HOT_START_MIN_NV`] variables on). Off, the marks only decide which
    /// violated row is added first.
    pub hot_start: bool,
}

impl Default for QpSettings {
    fn default() -> Self {
        QpSettings {
            tol_primal: 1e-10,
            tol_dependence: 1e-12,
            hot_start: true,
        }
    }
}

/// Result of one solve. `lambda` holds one multiplier per row (zero for inactive
/// rows), so `H x + q + G' lambda = 0` at a solution.
#[derive(Clone, Copy, Debug)]
pub struct QpSolution<const NV: usize, const NC: usize> {
    /// Primal solution (or last iterate when not solved).
    pub x: SVector<f64, NV>,
    /// Lagrange multipliers, one per row, in the order of the rows of `G`.
    /// When the status is [`QpStatus::Infeasible`] it holds instead a Farkas
    /// certificate of infeasibility: `y >= 0` with `G'y = 0` and `h'y < 0` (up
    /// to rounding), scaled so that the entry of the row that could not be
    /// added is 1.
    pub lambda: SVector<f64, NC>,
    /// Objective `1/2 x'Hx + q'x` at `x`.
    pub objective: f64,
    /// Outcome.
    pub status: QpStatus,
    /// Adds plus drops performed.
    pub iterations: u32,
    /// Indices of the active rows (first `n_active` entries valid).
    pub active: [u16; NV],
    /// Number of active rows.
    pub n_active: usize,
}

impl<const NV: usize, const NC: usize> QpSolution<NV, NC> {
    /// The active rows as a slice.
    pub fn active_set(&self) -> &[u16] {
        &self.active[..self.n_active.min(NV)]
    }
}

/// A QP of the form solved here, stored with fixed capacity: `m <= NC` rows are
/// used. `gt` holds `G` transposed (one constraint normal per column) so each row of
/// `G` is contiguous.
#[derive(Clone, Debug)]
pub struct DenseQp<const NV: usize, const NC: usize> {
    /// Linear cost term `q`.
    pub q: SVector<f64, NV>,
    /// `G` transposed: column `i` is row `i` of `G`.
    pub gt: SMatrix<f64, NV, NC>,
    /// Right-hand side `h`.
    pub h: SVector<f64, NC>,
    /// Number of rows in use.
    pub m: usize,
}

impl<const NV: usize, const NC: usize> Default for DenseQp<NV, NC> {
    fn default() -> Self {
        DenseQp {
            q: SVector::zeros(),
            gt: SMatrix::zeros(),
            h: SVector::zeros(),
            m: 0,
        }
    }
}

impl<const NV: usize, const NC: usize> DenseQp<NV, NC> {
    /// An empty QP (no rows, `q = 0`), all storage zero: usable in `const` and
    /// `static` initialisers (a `static` holding it lands in `.bss`).
    pub const EMPTY: Self = DenseQp {
        q: SVector::from_array_storage(ArrayStorage([[0.0; NV]; 1])),
        gt: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NC])),
        h: SVector::from_array_storage(ArrayStorage([[0.0; NC]; 1])),
        m: 0,
    };

    /// An empty QP with linear term `q`.
    pub fn with_q(q: SVector<f64, NV>) -> Self {
        DenseQp {
            q,
            ..DenseQp::default()
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
    pub fn push_row(&mut self, g: &SVector<f64, NV>, h: f64) -> Result<(), ()> {
        // `gt` is column-major: `gt.data.0[i]` is column `i` of `gt`, row `i` of `G`.
        let (Some(col), Some(rhs)) = (self.gt.data.0.get_mut(self.m), self.h.get_mut(self.m))
        else {
            return Err(());
        };
        *col = (*g).into();
        *rhs = h;
        self.m += 1;
        Ok(())
    }

    /// Row `i` of `G` (a column of `gt`).
    ///
    /// # Panics
    ///
    /// If `i >= NC`; see [`DenseQp::get_row`] for the non-panicking form.
    pub fn row(&self, i: usize) -> SVector<f64, NV> {
        self.gt.column(i).into_owned()
    }

    /// Row `i` as `(g_i, h_i)`, or `None` when `i >= NC` (rows `m..NC` are unused
    /// but exist).
    pub fn get_row(&self, i: usize) -> Option<(SVector<f64, NV>, f64)> {
        let g = self.gt.data.0.get(i)?;
        let h = self.h.get(i)?;
        Some((SVector::from(*g), *h))
    }

    /// The rows in use, `(g_i, h_i)` for `i = 0..m`, in order.
    pub fn rows(&self) -> impl Iterator<Item = (SVector<f64, NV>, f64)> + '_ {
        let m = self.m.min(NC);
        // `gt` is column-major: `gt.data.0[i]` is column `i` of `gt`, row `i` of `G`.
        self.gt.data.0[..m]
            .iter()
            .zip(&self.h.as_slice()[..m])
            .map(|(g, h)| (SVector::from(*g), *h))
    }

    /// The used rows with their Euclidean norms: `(g_i, h_i, |g_i|)`.
    pub fn rows_with_norm(&self) -> impl Iterator<Item = (SVector<f64, NV>, f64, f64)> + '_ {
        self.rows().map(|(g, h)| {
            let n = g.norm();
            (g, h, n)
        })
    }

    /// Largest violation `max_i (g_i x - h_i)^+` over the used rows, unscaled.
    pub fn max_violation(&self, x: &SVector<f64, NV>) -> f64 {
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
/// [`DualActiveSet::prepare_rows`] for [`DualActiveSet::solve_prepared`].
#[derive(Clone, Debug)]
pub struct RowNorms<const NC: usize> {
    /// `|g_i|^2`, in the units of `G` squared (no square root or division, so
    /// the pass over all rows is cheap; the violation test squares the slack).
    norm2: [f64; NC],
    /// `1 / |L^-1 g_i|`, 0 = not computed yet.
    inv_hnorm: [f64; NC],
    /// Rows covered.
    m: usize,
    /// Every entry of the covered rows is finite.
    finite: bool,
}

impl<const NC: usize> RowNorms<NC> {
    /// Squared Euclidean norms of the used rows of `qp` (H^-1 norms not
    /// computed).
    fn euclidean<const NV: usize>(qp: &DenseQp<NV, NC>) -> Self {
        let m = qp.m.min(NC);
        let mut rows = RowNorms {
            norm2: [0.0; NC],
            inv_hnorm: [0.0; NC],
            m,
            finite: true,
        };
        for (g, n2) in qp.gt.data.0.iter().zip(&mut rows.norm2).take(m) {
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

/// The solver: the factored Hessian and the settings. Build once per Hessian;
/// `solve` takes `&self`.
#[derive(Clone, Debug)]
pub struct DualActiveSet<const NV: usize, const NC: usize> {
    H: SMatrix<f64, NV, NV>,
    /// `L^-1` with `H = L L'`: lower triangular, entries above the diagonal
    /// exactly zero. Its transpose `J0 = L^-T` starts `J` in every solve.
    Linv: SMatrix<f64, NV, NV>,
    /// `L^-1` (so `H`) is diagonal: products with `L^-1` and `L^-T` cost `NV`
    /// instead of `NV^2`.
    linv_diag: bool,
    settings: QpSettings,
}

impl<const NV: usize, const NC: usize> DualActiveSet<NV, NC> {
    /// A placeholder with `H = 0`, `L^-1 = 0` and zero tolerances, all storage
    /// zero, for `const` and `static` initialisers (e.g. an unconfigured
    /// controller). Not a solver: overwrite it with one from
    /// [`DualActiveSet::new`] before solving (its solves never panic but mean
    /// nothing).
    pub const PLACEHOLDER: Self = DualActiveSet {
        H: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
        Linv: SMatrix::from_array_storage(ArrayStorage([[0.0; NV]; NV])),
        linv_diag: false,
        settings: QpSettings {
            tol_primal: 0.0,
            tol_dependence: 0.0,
            hot_start: false,
        },
    };

    /// Factors `H` (symmetric positive definite) once.
    pub fn new(H: &SMatrix<f64, NV, NV>, settings: QpSettings) -> Result<Self, HessianError> {
        const {
            assert!(NV > 0, "NV must be positive");
            assert!(NV <= u16::MAX as usize && NC <= u16::MAX as usize);
        }
        if H.iter().any(|v| !v.is_finite()) {
            return Err(HessianError::NotFinite);
        }
        let scale = H.amax().max(f64::MIN_POSITIVE);
        // |H_ij - H_ji| for i > j; `cols[j][i]` is H_ij (column-major), read
        // with checked access (bounds the optimiser could not prove for every
        // NV, see nopanic/).
        let cols = &H.data.0;
        for (j, col) in cols.iter().enumerate() {
            for (i, &hij) in col.iter().enumerate().skip(j + 1) {
                let hji = cols.get(i).and_then(|c| c.get(j)).copied().unwrap_or(hij);
                if (hij - hji).abs() > 1e-12 * scale {
                    return Err(HessianError::NotSymmetric);
                }
            }
        }
        let chol = nalgebra::linalg::Cholesky::new(*H).ok_or(HessianError::NotPositiveDefinite)?;
        let L = chol.l();
        let mut J0 = SMatrix::<f64, NV, NV>::identity();
        if !L.transpose().solve_upper_triangular_mut(&mut J0) || J0.iter().any(|v| !v.is_finite()) {
            return Err(HessianError::NotPositiveDefinite);
        }
        // L^-1 with exact zeros above the diagonal.
        let mut Linv = J0.transpose();
        for (j, col) in Linv.data.0.iter_mut().enumerate() {
            for v in col.iter_mut().take(j) {
                *v = 0.0;
            }
        }
        let linv_diag = Linv
            .data
            .0
            .iter()
            .enumerate()
            .all(|(j, col)| col.iter().enumerate().all(|(k, &v)| k == j || v == 0.0));
        Ok(DualActiveSet {
            H: *H,
            Linv,
            linv_diag,
            settings,
        })
    }

    /// The same solver with [`QpSettings::hot_start`] off (the marks then only
    /// decide which violated row is added first).
    pub fn without_hot_start(&self) -> Self {
        let mut s = self.clone();
        s.settings.hot_start = false;
        s
    }

    /// The Hessian this solver was built for.
    pub fn hessian(&self) -> &SMatrix<f64, NV, NV> {
        &self.H
    }

    /// The settings.
    pub fn settings(&self) -> &QpSettings {
        &self.settings
    }

    /// Objective `1/2 x'Hx + q'x`.
    pub fn objective(&self, q: &SVector<f64, NV>, x: &SVector<f64, NV>) -> f64 {
        let mut xhx = 0.0;
        for (col, xj) in self.H.data.0.iter().zip(x.iter()) {
            xhx += xj * dot(col, &x.data.0[0]);
        }
        0.5 * xhx + dot(&q.data.0[0], &x.data.0[0])
    }

    /// `L^-1 g` (`= J0' g`) as column axpys (no reductions);
    /// `NV` products when `H` is diagonal.
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    pub(crate) fn linv_mul(&self, g: &[f64; NV]) -> [f64; NV] {
        let mut w = [0.0f64; NV];
        for (k, (col, &gk)) in self.Linv.data.0.iter().zip(g).enumerate() {
            if self.linv_diag {
                w[k] = col[k] * gk;
            } else {
                // zeros above the diagonal included: fixed length, vectorised
                for (wi, c) in w.iter_mut().zip(col) {
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
    pub(crate) fn linvt_mul(&self, w: &[f64; NV]) -> [f64; NV] {
        let mut x = [0.0f64; NV];
        for (k, (xk, col)) in x.iter_mut().zip(&self.Linv.data.0).enumerate() {
            *xk = if self.linv_diag {
                col[k] * w[k]
            } else {
                dot(col, w) // zeros above the diagonal included: no branches
            };
        }
        x
    }

    /// Solves the QP `qp` with at most `max_iter` adds plus drops. `prefer[i]` marks
    /// row `i` as expected active (warm start); pass all `false` for a cold start.
    pub fn solve(
        &self,
        qp: &DenseQp<NV, NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        // The H^-1 norms are left to the solve, which computes them only for
        // rows found violated.
        let mut rows = RowNorms::euclidean(qp);
        self.solve_with(
            qp,
            &qp.h.data.0[0],
            &[false; NC],
            &mut rows,
            prefer,
            max_iter,
        )
    }

    /// [`DualActiveSet::solve`] on a selection of `qp`'s rows with other
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
        qp: &DenseQp<NV, NC>,
        h: &SVector<f64, NC>,
        enabled: &[bool; NC],
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        let mut excluded = [false; NC];
        for (x, &on) in excluded.iter_mut().zip(enabled) {
            *x = !on;
        }
        let mut rows = RowNorms::euclidean(qp);
        self.solve_with(qp, &h.data.0[0], &excluded, &mut rows, prefer, max_iter)
    }

    /// The per-row data of `qp`'s constraint matrix that [`DualActiveSet::solve`]
    /// otherwise computes in every call (`m` Euclidean and `m` H^-1 row norms):
    /// prepare it once when `G` stays the same over many solves (only `q` and `h`
    /// change, as in a linear MPC with fixed constraints) and pass it to
    /// [`DualActiveSet::solve_prepared`].
    pub fn prepare_rows(&self, qp: &DenseQp<NV, NC>) -> RowNorms<NC> {
        let mut rows = RowNorms::euclidean(qp);
        for ((g, &n2), inv_hn) in qp
            .gt
            .data
            .0
            .iter()
            .zip(&rows.norm2)
            .zip(&mut rows.inv_hnorm)
            .take(rows.m)
        {
            if n2 > ZERO_ROW2 {
                *inv_hn = self.inv_hnorm(g, n2);
            }
        }
        rows
    }

    /// [`DualActiveSet::solve`] with the row data prepared by
    /// [`DualActiveSet::prepare_rows`] from a QP with the same rows of `G` (same
    /// `m`; `q` and `h` may differ). Same result as `solve`, less work per call.
    /// A `rows` prepared for a different `m` gives [`QpStatus::NumericalError`].
    pub fn solve_prepared(
        &self,
        qp: &DenseQp<NV, NC>,
        rows: &RowNorms<NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        let mut rows = rows.clone();
        if rows.m != qp.m.min(NC) {
            rows.finite = false;
        }
        self.solve_with(
            qp,
            &qp.h.data.0[0],
            &[false; NC],
            &mut rows,
            prefer,
            max_iter,
        )
    }

    /// `1 / |L^-1 g|` for a row with `|g|^2 = n2 > 0`.
    // Inlined on hosts (vectorised into the callers); the compiler decides on
    // bare-metal targets, where one out-of-line copy saves flash.
    #[cfg_attr(not(target_os = "none"), inline(always))]
    fn inv_hnorm(&self, g: &[f64; NV], n2: f64) -> f64 {
        let w = self.linv_mul(g);
        let hn = crate::float::sqrt(dot(&w, &w));
        // L^-1 is nonsingular, so hn > 0 for a non-zero row (barring underflow,
        // where the Euclidean norm stands in).
        if hn > 0.0 {
            1.0 / hn
        } else {
            1.0 / crate::float::sqrt(n2)
        }
    }

    /// The solve proper, with the right-hand side `h` (`qp.h` or another), the
    /// rows `excluded[i]` left out, the Euclidean row norms in `rows` and the
    /// H^-1 norms there or computed on demand (0 = not yet).
    fn solve_with(
        &self,
        qp: &DenseQp<NV, NC>,
        h: &[f64; NC],
        excluded: &[bool; NC],
        norms: &mut RowNorms<NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        let m = qp.m.min(NC);
        let q = &qp.q.data.0[0];
        if !norms.finite
            || !q.iter().all(|v| v.is_finite())
            || !h
                .iter()
                .zip(excluded)
                .take(m)
                .all(|(v, &out)| out || v.is_finite())
        {
            return active_set::stopped(QpStatus::NumericalError, None);
        }
        let tol = self.settings.tol_primal;
        let RowNorms {
            norm2, inv_hnorm, ..
        } = norms;
        let zero_infeasible = h
            .iter()
            .zip(norm2.iter())
            .zip(excluded)
            .take(m)
            .position(|((&hi, &n2), &out)| !out && n2 <= ZERO_ROW2 && hi < -tol);
        if zero_infeasible.is_some() {
            // 0'x <= h with h < 0: nothing satisfies it; y = e_i certifies it.
            return active_set::stopped(QpStatus::Infeasible, zero_infeasible);
        }
        // Unconstrained minimiser x = -J0 J0' q = -L^-T L^-1 q.
        let mut x = self.linvt_mul(&self.linv_mul(q));
        for v in x.iter_mut() {
            *v = -*v;
        }
        let mut J = self.Linv.transpose();
        let mut R = SMatrix::<f64, NV, NV>::zeros();
        let (mut d, mut z) = ([0.0; NV], [0.0; NV]);
        let mut factor = Orthogonal {
            solver: self,
            rows: &qp.gt.data.0,
            h,
            norm2,
            inv_hnorm,
            tol2: tol * tol,
            x,
            J: &mut J,
            R: &mut R,
            d: &mut d,
            z: &mut z,
            dependent: false,
        };
        // Rows left out are never scanned: they start (and stay) blocked as if
        // active, but never enter the active list.
        let hot = self.settings.hot_start;
        let Some(it) = active_set::iterate(&mut factor, m, *excluded, prefer, max_iter, hot) else {
            // The orthogonal factor never asks for a restart.
            return active_set::stopped(QpStatus::NumericalError, None);
        };
        let x = factor.x;
        it.solution(x, self.objective(&qp.q, &SVector::from(x)), |_| 1.0)
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
    /// like `qp`'s rows; see [`DualActiveSet::solve_selected`]. The provided
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

/// The built-in backend: [`DualActiveSet::solve`].
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

#[cfg(test)]
mod tests;
