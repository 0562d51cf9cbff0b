//! What a solve returns ([`QpStatus`], [`QpSolutionOf`]) and the
//! allocations it needs ([`QpAllocator`]): shared by the iteration
//! (`active_set.rs`) and the solvers built on it (`qp.rs`, `ldp.rs`), which
//! re-export them from [`crate::qp`].

#[cfg(feature = "alloc")]
use nalgebra::Dyn;
use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, OVector};

/// The allocations the solver needs for `NV` variables and `NC` rows: every
/// `DefaultAllocator` over `Const` sizes has them (no heap), and so has the
/// one over `Dyn` with nalgebra's `alloc` feature.
pub trait QpAllocator<NV: Dim, NC: Dim>:
    Allocator<NV> + Allocator<NC> + Allocator<NV, NV> + Allocator<NV, NC> + Allocator<NC, NC>
{
}

impl<NV: Dim, NC: Dim, A> QpAllocator<NV, NC> for A where
    A: Allocator<NV> + Allocator<NC> + Allocator<NV, NV> + Allocator<NV, NC> + Allocator<NC, NC>
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
    /// Lagrange multipliers, one per row, in the order of the rows of `G`
    /// (`>= 0` for inequality rows, either sign for equality rows).
    /// When the status is [`QpStatus::Infeasible`] it holds instead a Farkas
    /// certificate of infeasibility: `y` with `G'y = 0` and `h'y < 0` (up
    /// to rounding), `>= 0` on inequality rows, scaled so that the entry of
    /// the row that could not be added is 1 (or -1 for an equality row
    /// violated from below).
    pub lambda: OVector<f64, NC>,
    /// Objective `1/2 x'Hx + q'x` at `x`.
    pub objective: f64,
    /// Outcome.
    pub status: QpStatus,
    /// Adds plus drops performed.
    pub iterations: u32,
    /// Indices of the active rows (first `n_active` entries valid; the
    /// equality rows first).
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
}

/// [`QpSolutionOf`] with run-time sizes (feature `alloc`).
#[cfg(feature = "alloc")]
pub type QpSolutionDyn = QpSolutionOf<Dyn, Dyn>;
