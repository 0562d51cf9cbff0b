//! # ldcbf-reference
//!
//! Independent reference for the controller's QP solver: the same QPs, built by
//! the controller's own assembly code, solved by the interior-point solver
//! [Clarabel](https://clarabel.org), and compared with our dense dual
//! active-set solution.
//!
//! * [`DenseProblem`] holds any dense QP of the qpbenchmark form
//!   `min 1/2 x'Px + q'x  s.t.  Gx <= h, Ax = b, lb <= x <= ub` (row-major; any
//!   of the last three absent), built from a controller [`Assembly`]
//!   ([`DenseProblem::from_assembly`]) or read from the npz layout of the
//!   external test set ([`DenseProblem::from_npz`]).
//! * [`DenseProblem::stacked`] gives it as one row list, equalities first, then
//!   `G`, then the finite bounds ([`Stacked`]): the solvers' input, in whose
//!   order all multipliers come ([`Stacked::split_multipliers`] maps them back).
//!   [`ProblemView`] is the same problem borrowed (slices): it defines the
//!   stacked order once and writes the rows straight into the solver's types.
//! * [`solve_clarabel`] solves it with Clarabel (verbose off, tight tolerances).
//! * [`solve_own`] solves it with [`DualActiveSet`] at a fixed size, [`solve_own_dyn`] with the run-time-sized instance (no
//!   equality rows).
//! * [`compare_stacked`] checks any solver's answer, given as slices
//!   ([`Candidate`]), against Clarabel's; [`kkt_stacked`] measures the KKT
//!   residuals of a primal-dual pair, [`farkas_holds`] an infeasibility
//!   certificate. [`compare`] and [`kkt`] are the same checks for the
//!   fixed-size [`QpSolution`] (docs/maths.md §3 scaling).
//! * [`random_problem`] makes deterministic random QPs, feasible or infeasible
//!   by construction ([`QpKind`]).
//! * [`ClarabelBackend`] is a QP backend of the controller
//!   ([`Controller::with_backend`]) so a whole closed loop can be run with the
//!   reference solver.
//!
//! [`Controller::with_backend`]: ldcbf_controller::Controller::with_backend
#![allow(non_snake_case)]

// Named in the crate docs only (intra-doc links).
#[cfg(doc)]
use ldcbf_controller::{Assembly, DualActiveSet, QpSolution};

mod check;
mod clarabel_solve;
mod equivalence;
mod npy_header;
mod npz;
mod problem;
mod random;
mod stacked;
mod view;

pub use check::{
    AGREEMENT_TOL, Candidate, Farkas, StackedAgreement, StackedKkt, compare_stacked, farkas_holds,
    farkas_residuals, kkt_stacked,
};
pub use clarabel_solve::{ClarabelBackend, RefSolution, RefStatus, solve_clarabel};
pub use equivalence::{Agreement, Kkt, compare, kkt, solve_own, solve_own_dyn};
pub use npz::{MAX_NPZ_BYTES, MAX_QP_ROWS, MAX_QP_VARIABLES};
pub use problem::{DenseProblem, ProblemError, SizedQp};
pub use random::{QpKind, random_problem};
pub use stacked::{Multipliers, RowOrigin, Stacked};
pub use view::ProblemView;

#[cfg(test)]
mod tests;
