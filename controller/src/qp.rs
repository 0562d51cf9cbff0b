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
//! re-factorisation, no normal equations).
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
//! previous cycle's active set). Among the violated rows the solver adds a marked
//! one first. Any violated row is a valid choice in the dual method, so the marks
//! change the path (usually shortening it), never the solution.
//!
//! Infeasibility: a violated row whose normal lies in the span of the active
//! normals and for which no active multiplier can decrease proves the constraint
//! set empty (Goldfarb & Idnani, step 2(c)(i)); the solver reports
//! [`QpStatus::Infeasible`].
#![allow(non_snake_case)]

use nalgebra::{ArrayStorage, SMatrix, SVector};

/// Rows whose squared Euclidean norm is not above this (it is 0 for an exactly
/// zero row or one whose squares underflow, `|g| < ~1e-162`) are treated as zero
/// rows: satisfied when `h_i >= -tol`, infeasible otherwise.
pub(crate) const ZERO_ROW2: f64 = 0.0;

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
            qp.h.as_slice(),
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
        self.solve_with(qp, h.as_slice(), &excluded, &mut rows, prefer, max_iter)
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
            qp.h.as_slice(),
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
        h: &[f64],
        excluded: &[bool; NC],
        norms: &mut RowNorms<NC>,
        prefer: &[bool; NC],
        max_iter: u32,
    ) -> QpSolution<NV, NC> {
        let m = qp.m.min(NC);
        let mut sol = QpSolution {
            x: SVector::zeros(),
            lambda: SVector::zeros(),
            objective: 0.0,
            status: QpStatus::NumericalError,
            iterations: 0,
            active: [0; NV],
            n_active: 0,
        };
        let rows = &qp.gt.data.0; // `rows[i]` is row `i` of `G`
        let q = &qp.q.data.0[0];
        if !norms.finite
            || h.len() < m
            || !q.iter().all(|v| v.is_finite())
            || !h
                .iter()
                .zip(excluded)
                .take(m)
                .all(|(v, &out)| out || v.is_finite())
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
        let RowNorms {
            norm2, inv_hnorm, ..
        } = norms;
        let zero_infeasible = h
            .iter()
            .zip(norm2.iter())
            .zip(excluded)
            .take(m)
            .position(|((&hi, &n2), &out)| !out && n2 <= ZERO_ROW2 && hi < -tol);
        if let Some(i) = zero_infeasible {
            // 0'x <= h with h < 0: nothing satisfies it; y = e_i certifies it.
            sol.status = QpStatus::Infeasible;
            if let Some(y) = sol.lambda.get_mut(i) {
                *y = 1.0;
            }
            return sol;
        }

        // Unconstrained minimiser x = -J0 J0' q = -L^-T L^-1 q.
        let mut J = self.Linv.transpose();
        let mut x = self.linvt_mul(&self.linv_mul(q));
        for v in x.iter_mut() {
            *v = -*v;
        }
        let mut R = SMatrix::<f64, NV, NV>::zeros();
        let mut u = [0.0f64; NV]; // multipliers of the active rows
        let mut act = [0u16; NV];
        // Rows left out are never scanned: they start (and stay) marked as if
        // active, but never enter `act`.
        let mut is_active = *excluded;
        let mut nact: usize = 0;
        let mut iters: u32 = 0;
        // On infeasibility: the row `p` and `-r` of the active rows (see below).
        let mut farkas: Option<(usize, [f64; NV])> = None;

        let status = 'outer: loop {
            // Step 1: choose a violated row (marked rows first).
            let mut best: Option<usize> = None;
            let mut best_v = 0.0;
            let mut best_pref: Option<usize> = None;
            let mut best_pref_v = 0.0;
            for i in 0..m {
                // `i < m <= NC`: every index below is in bounds.
                if is_active[i] || norm2[i] <= ZERO_ROW2 {
                    continue;
                }
                let g = &rows[i];
                let slack = h[i] - dot(g, &x);
                if !slack.is_finite() {
                    break 'outer QpStatus::NumericalError;
                }
                if slack >= 0.0 || slack * slack <= tol2 * norm2[i] {
                    continue; // satisfied to tolerance
                }
                if inv_hnorm[i] == 0.0 {
                    inv_hnorm[i] = self.inv_hnorm(g, norm2[i]);
                }
                let s = slack * inv_hnorm[i];
                if s < best_v {
                    best_v = s;
                    best = Some(i);
                }
                if prefer[i] && s < best_pref_v {
                    best_pref_v = s;
                    best_pref = Some(i);
                }
            }
            let p = match best_pref.or(best) {
                None => break QpStatus::Solved,
                Some(p) => p,
            };
            // `p < m <= NC`, so the row exists.
            let (Some(gp), Some(&hp)) = (rows.get(p), h.get(p)) else {
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
                let nact_c = nact.min(NV);
                // d = J' n_p with the GI normal n_p = -g_p (n_p'x >= -h_p).
                let mut d = [0.0f64; NV];
                for (dj, col) in d.iter_mut().zip(&J.data.0) {
                    *dj = -dot(col, gp);
                }
                // z = J2 d2: component of the step outside the active span.
                let mut z = [0.0f64; NV];
                let mut d2sq = 0.0;
                for (col, &dj) in J.data.0.iter().zip(d.iter()).skip(nact_c) {
                    for (zk, c) in z.iter_mut().zip(col) {
                        *zk += c * dj; // column j of J, j >= nact
                    }
                    d2sq += dj * dj;
                }
                // r = R^-1 d1 (back substitution on the active block). Counting
                // down from the constant NV lets the compiler see every i < NV.
                let mut r = [0.0f64; NV];
                for i in (0..NV).rev().filter(|&i| i < nact_c) {
                    let mut acc = d[i];
                    for k in (i + 1)..nact_c {
                        acc -= R[(i, k)] * r[k];
                    }
                    r[i] = acc / R[(i, i)];
                }
                // Partial (dual) step length t1 and the row to drop.
                let mut t1 = f64::INFINITY;
                let mut drop: Option<usize> = None;
                let rmax = r[..nact_c].iter().fold(0.0f64, |a, b| a.max(b.abs()));
                for i in 0..nact_c {
                    if r[i] > 1e-14 * rmax.max(1.0) {
                        let t = u[i] / r[i];
                        if t < t1 {
                            t1 = t;
                            drop = Some(i);
                        }
                    }
                }
                // Full (primal) step length t2.
                let dn = crate::float::sqrt(dot(&d, &d));
                let dependent = crate::float::sqrt(d2sq) <= self.settings.tol_dependence * dn;
                let slack_p = hp - dot(gp, &x); // < 0 while violated
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
                    let mut neg_r = r;
                    for y in neg_r.iter_mut() {
                        *y = -*y;
                    }
                    farkas = Some((p, neg_r));
                    break 'outer QpStatus::Infeasible;
                }
                let t = t1.min(t2);
                iters += 1;
                // Multipliers move along (-r, 1).
                for i in 0..nact_c {
                    u[i] -= t * r[i];
                }
                u_new += t;
                if !dependent {
                    for (xk, zk) in x.iter_mut().zip(&z) {
                        *xk += t * zk;
                    }
                }
                if t2 <= t1 {
                    // Full step: p becomes active.
                    // `add_row` fails when the active set is full (nact == NV).
                    let (true, Some(a), Some(un), Some(flag)) = (
                        self.add_row(&mut J, &mut R, nact_c, &d),
                        act.get_mut(nact_c),
                        u.get_mut(nact_c),
                        is_active.get_mut(p),
                    ) else {
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
                Self::drop_row(&mut J, &mut R, nact_c, l);
                // Close the gap at `l` in the active list and its multipliers.
                let last = nact_c.saturating_sub(1);
                for i in l..last {
                    act[i] = act[i + 1];
                    u[i] = u[i + 1];
                }
                nact = last;
            }
        };

        sol.x = SVector::from(x);
        let nact = nact.min(NV);
        // Multipliers of the active rows, or the Farkas certificate.
        let weights = match farkas {
            Some((p, neg_r)) => {
                if let Some(y) = sol.lambda.get_mut(p) {
                    *y = 1.0;
                }
                neg_r
            }
            None => u,
        };
        for (&row, &w) in act[..nact].iter().zip(&weights[..nact]) {
            if let Some(lambda) = sol.lambda.get_mut(usize::from(row)) {
                *lambda = w.max(0.0); // row < m <= NC: always there
            }
        }
        sol.active = act;
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

    /// Adds a row whose `d = J' n` is given: one Householder reflection of
    /// columns `nact..NV` of `J` maps `d[nact..]` to `alpha e_nact` (`|alpha| =
    /// |d[nact..]|`), and `d[..nact], alpha` becomes column `nact` of `R`. Half
    /// the flops of the equivalent Givens sweep, and all of them vectorise.
    fn add_row(
        &self,
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
        // Column `nact` of R gets d[..=nact] (checked access, as in drop_row).
        let Some(col) = R.data.0.get_mut(nact) else {
            return false;
        };
        for (r, &di) in col.iter_mut().zip(&d).take(nact + 1) {
            *r = di;
        }
        col.get(nact).is_some_and(|&r| r != 0.0 && r.is_finite())
    }

    /// Removes active row `l` (of `nact`): deletes column `l` of `R` and restores
    /// the triangle with Givens rotations, applied to `J` as well.
    fn drop_row(J: &mut SMatrix<f64, NV, NV>, R: &mut SMatrix<f64, NV, NV>, nact: usize, l: usize) {
        let nact = nact.min(NV); // invariant of `solve`, stated for the compiler
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

/// `a . b` with four partial sums (independent add chains; `N` is a constant, so
/// the loop unrolls and vectorises without bounds checks).
#[inline(always)]
pub(crate) fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut acc = [0.0f64; 2];
    for k in 0..N {
        acc[k % 2] += a[k] * b[k];
    }
    acc[0] + acc[1]
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
}
