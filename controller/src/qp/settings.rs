//! What a solve may be told ([`QpSettings`]: tolerances, the iteration
//! limit, the hot start) and why a Hessian is refused ([`HessianError`]);
//! the thresholds that decide what is compiled in for a size.

use nalgebra::Dim;

/// Error from [`DualActiveSetOf::new`](super::DualActiveSetOf::new): the Hessian cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HessianError {
    /// An entry of `H` is NaN or infinite.
    NotFinite,
    /// `H` is not symmetric to a relative 1e-12.
    NotSymmetric,
    /// The Cholesky factorisation failed: `H` is not positive definite (nor,
    /// where the proximal iterations are compiled in, positive semidefinite
    /// to [`PROX_EPS`](super::PROX_EPS)).
    NotPositiveDefinite,
    /// `H` has no rows, or more than 65535 (only possible with run-time
    /// sizes; the static sizes are checked at compile time).
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

/// Tolerances, the iteration limit and options of the solver. The tolerances
/// are absolute, applied to rows scaled to unit norm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QpSettings {
    /// A row counts as violated when `(h_i - g_i x) / |g_i| < -tol_primal`.
    pub tol_primal: f64,
    /// Relative size below which the component of a new normal outside the span of
    /// the active normals is taken as zero (linear dependence).
    pub tol_dependence: f64,
    /// Hot start: the rows marked in `prefer` enter the active set together
    /// before the first row scan (module docs; compiled in from
    /// [`HOT_START_MIN_NV`](super::HOT_START_MIN_NV) variables on). Off, the marks only decide which
    /// violated row is added first.
    pub hot_start: bool,
    /// Iteration limit of one solve: at most this many adds plus drops
    /// (>= 1); a solve that needs more stops with
    /// [`QpStatus::IterationLimit`](crate::solution::QpStatus::IterationLimit).
    pub max_iter: u32,
}

impl Default for QpSettings {
    fn default() -> Self {
        QpSettings {
            tol_primal: 1e-10,
            tol_dependence: 1e-12,
            hot_start: true,
            max_iter: 1000,
        }
    }
}

impl QpSettings {
    /// Largest tolerance [`QpSettings::validate`] accepts: a row violated by
    /// more than this (scaled to unit norm) is never taken as satisfied, and a
    /// component of a normal above it never as dependent.
    pub const MAX_TOL: f64 = 1e-3;

    /// Checks the settings: each tolerance finite and in `(0, MAX_TOL)`,
    /// `max_iter >= 1`. The error is `(field, requirement)` for the first bad
    /// one. Every interface that takes settings from a user (the
    /// controller's `Config`, the C API, Python's `solve_qp`) checks them
    /// here.
    pub fn validate(&self) -> Result<(), (&'static str, &'static str)> {
        let ok = |t: f64| t.is_finite() && t > 0.0 && t < Self::MAX_TOL;
        if !ok(self.tol_primal) {
            return Err(("tol_primal", "must be in (0, 1e-3)"));
        }
        if !ok(self.tol_dependence) {
            return Err(("tol_dependence", "must be in (0, 1e-3)"));
        }
        if self.max_iter == 0 {
            return Err(("max_iter", "must be >= 1"));
        }
        Ok(())
    }
}

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

/// The proximal weight relative to the largest entry of `H` (DAQP's default
/// `eps_prox` is `1e-6`).
pub const PROX_EPS: f64 = 1e-6;

/// Whether the proximal iterations are compiled in for `NV` variables (a
/// constant for the static sizes).
#[inline(always)]
pub(super) fn proximal_capable<NV: Dim>() -> bool {
    NV::try_to_usize().is_none_or(|n| n >= HOT_START_MIN_NV)
}
