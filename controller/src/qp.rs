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
//! and `NC` (row capacity) are [`Dim`](nalgebra::Dim)s. With `Const<N>` every buffer is a
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

#[cfg(feature = "alloc")]
pub use crate::solution::QpSolutionDyn;
pub use crate::solution::{QpAllocator, QpSolution, QpSolutionOf, QpStatus};

// The files in one-way layers, each naming only files of the layers below
// it (`controller/tests/qp_layering.rs` lists them and checks it), from the
// bottom up:
// - the data: `settings` (and size thresholds), `updates` (of the factor
//   `J`, `R`), `kept` (the rows a factor resumes from), `dense` (the QP),
//   `bounds`, `solver` (the Hessian's factor `L^-1`), `spans`, `norms`,
//   `start` (the checks a solve starts with), `gram` (the hot start's Gram
//   factor);
// - the factor of the active set, `orthogonal`; the hot start's `guess` on
//   it; one `step` of the dual iteration on it;
// - one solve: `resolve` (its start from a kept factor), `store` (where it
//   keeps the factor), `dual` (the solve);
// - above one solve: `reprobe` (the probes that continue from the last
//   one's factor), `proximal` (the outer loop for a semidefinite `H`),
//   `solve` (the entry points), `backend` (the controller's trait).
#[macro_use]
mod start;
mod backend;
mod bounds;
mod dense;
mod dual;
mod gram;
mod guess;
mod kept;
mod norms;
mod orthogonal;
mod proximal;
mod reprobe;
mod resolve;
mod settings;
mod solve;
mod solver;
mod spans;
mod step;
mod store;
mod updates;

pub use backend::{OwnSolver, QpBackend};
#[cfg(feature = "alloc")]
pub use bounds::SimpleBoundsDyn;
pub use bounds::{SimpleBounds, SimpleBoundsOf};
#[cfg(feature = "alloc")]
pub use dense::DenseQpDyn;
pub use dense::{DenseQp, DenseQpOf};
#[cfg(feature = "alloc")]
pub use norms::RowNormsDyn;
pub use norms::{RowNorms, RowNormsOf};
pub use proximal::{PROX_MAX_OUTER, PROX_TOL};
pub use reprobe::{Reprobe, ReprobeOf};
pub(crate) use settings::ZERO_ROW2;
pub use settings::{HOT_START_MIN_NV, HessianError, PROX_EPS, QpSettings};
#[cfg(feature = "alloc")]
pub use solver::DualActiveSetDyn;
pub use solver::{DualActiveSet, DualActiveSetOf};

#[cfg(test)]
mod tests;
