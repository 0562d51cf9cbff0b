//! # ldcbf-controller
//!
//! A `#![no_std]`, allocation-free footstep planner for humanoid robots: a model
//! predictive controller on the 3D linear inverted pendulum (LIP) with heading,
//! kept out of convex obstacles by linear discrete control barrier functions
//! (LDCBF), after Peng et al., "Real-Time Safe Bipedal Robot Navigation using
//! Linear Discrete Control Barrier Functions" (arXiv 2411.03619).
//!
//! Each control cycle ([`Controller::step`]):
//!
//! 1. predicts the CoM state `x_0` at the end of the current step ([`lip`]);
//! 2. fixes the turning rate `omega_bar` and the headings `theta_k` ([`heading`]);
//! 3. selects the obstacles within `r_active`, nearest first, and linearises each
//!    as a half-plane at the boundary point closest to `p_0` ([`geometry`]);
//!    a caller with a large map passes only the candidates its spatial index
//!    finds around [`Controller::obstacle_query`] (the `candidates` of [`Controller::step`]),
//!    with the same result; an obstacle may move
//!    ([`CycleInput::obstacle_velocities`]): the half-plane at step end `k` is
//!    then the one moved with it to that step end's time;
//! 4. builds the condensed QP over the next `N` footsteps `f_0 .. f_{N-1}`
//!    ([`constraints`]), solved in the equivalent, well-conditioned variables
//!    `z = [p_1x, p_1y, ..., p_Nx, p_Ny]` (the predicted CoM positions, from which
//!    the footsteps follow exactly):
//!
//!    ```text
//!    minimise    sum_{k=1..N} |p_k - g|^2  =  1/2 z'Hz + q'z + const,  H = 2 I
//!    subject to  walking velocity, leg reachability, maneuverability (k = 0..N-1)
//!                h_j(p_{k+1}) >= (1 - gamma) h_j(p_k)   for each active obstacle j
//!    ```
//!
//!    `H` is constant and factored once;
//! 5. solves it with the dense dual active-set method of [`qp`] and returns the
//!    swing-foot target `f_0`, `omega_bar`, the predicted plan, a status and
//!    diagnostics ([`mpc`]). An infeasible QP is answered by the priority
//!    scheme of [`relax`] (reachability, then safety, then gait rows).
//!
//! Frames and units: everything is in the world frame W, in metres, seconds and
//! radians; headings are measured counter-clockwise from the world x axis.
//!
//! Sizes are const generics (horizon `N`, variables `NV = 2N`, row capacity `NC`,
//! obstacle capacity `NOBS`), checked against each other at compile time; see
//! [`mpc`] for the rules and [`PaperController`] for the paper's configuration.
//!
//! The maths of each step is in the repository's `docs/maths.md`; a whole
//! closed loop runs with `cargo run -p ldcbf-controller --example closed_loop`
//! (`examples/closed_loop.rs`). The enums that hosts print (statuses, command
//! sources, sides) have one name each: their `name()`.
#![no_std]
// One audited `asm!` (the FPU square root of `float`, feature `hw-sqrt`) is
// the only unsafe code; everything else stays safe.
#![deny(unsafe_code)]
#![warn(clippy::std_instead_of_core, clippy::alloc_instead_of_core)]

#[cfg(feature = "alloc")]
extern crate alloc;

mod active_set;
pub mod constraints;
pub mod geometry;
pub mod heading;
pub mod ldp;
mod linalg;
pub mod lip;
pub mod mpc;
mod names;
pub mod qp;
pub mod reach;
pub mod relax;
mod solution;

pub use nalgebra;
pub use reach::{Reach, ReachLimits};

pub use constraints::{Condensed, HalfPlane, RowId, RowKind};
pub use geometry::{
    ClosestPoint, ConvexPolygon, GeometryError, PointLocation, closest_point_point_polygon,
    convex_hull_into,
};
pub use heading::{HeadingPlan, plan_heading, wrap_angle};
pub use ldp::{LdpLoaded, LdpLoadedOf, LdpSolver, LdpSolverOf};
#[cfg(feature = "alloc")]
pub use ldp::{LdpLoadedDyn, LdpSolverDyn};
pub use lip::Lip;
pub use mpc::{
    ActiveObstacle, Assembly, CommandSource, Config, ConfigError, Controller, CycleInfo,
    CycleInput, CycleOutput, CycleStatus, FieldError, FieldValue, InputError, LipState,
    NO_SPEED_CAP, ObstacleQuery, PaperController, Plan, Prediction, RecordedInput, RobotController,
    Side, constraint_capacity,
};
pub use qp::{
    DenseQp, DenseQpOf, DualActiveSet, DualActiveSetOf, HessianError, OwnSolver, QpAllocator,
    QpBackend, QpSettings, QpSolution, QpSolutionOf, QpStatus, RowNorms, RowNormsOf, SimpleBounds,
    SimpleBoundsOf,
};
#[cfg(feature = "alloc")]
pub use qp::{DenseQpDyn, DualActiveSetDyn, QpSolutionDyn, RowNormsDyn, SimpleBoundsDyn};
