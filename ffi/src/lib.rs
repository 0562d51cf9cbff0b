//! # ldcbf-ffi: the C API of the LDCBF footstep controller
//!
//! A C interface to [`ldcbf_controller`]'s [`RobotController`] (horizon
//! [`LDCBF_HORIZON`] = 3, up to [`LDCBF_MAX_ACTIVE_OBSTACLES`] = 8 obstacles in
//! each QP, room for the foot-clearance rows): the controller the simulator
//! runs. Sizes are fixed at compile time; nothing is allocated. The header
//! `include/ldcbf.h` is generated from this file by cbindgen (the test
//! `tests/header.rs` fails if the committed header is stale).
//!
//! ## Use from C
//!
//! ```c
//! _Alignas(LDCBF_CONTROLLER_ALIGN) static unsigned char storage[LDCBF_CONTROLLER_SIZE];
//! LdcbfController *ctl;
//! LdcbfConfig cfg;
//! ldcbf_config_default(&cfg);
//! ldcbf_init(storage, sizeof storage, &ctl);   // in place, no allocation
//! ldcbf_configure(ctl, &cfg);                  // validates, precomputes
//! // every control cycle:
//! ldcbf_step(ctl, &input, points, counts, n_obstacles, &out);
//! ```
//!
//! ## Frames and units
//!
//! Everything is in the world frame W (x, y in the horizontal plane), in
//! metres, seconds and radians; headings are counter-clockwise from the world
//! x axis. A 2-vector is a `double[2]` holding `{x, y}`.
//!
//! ## Errors and statuses
//!
//! Every function that can fail returns an [`LdcbfResult`]: [`LdcbfResult::Ok`]
//! or a caller mistake (a NULL or misaligned pointer, storage too small, a
//! handle that [`ldcbf_init`] did not initialise, an invalid configuration or
//! obstacle, ...). On any result other than `Ok` nothing is written through
//! the output pointers and the controller's state is unchanged;
//! [`ldcbf_last_error`] describes the last error of a controller in words
//! (which configuration field, which obstacle). The outcome of a control cycle
//! is separate: [`LdcbfOutput::status`] ([`LdcbfCycleStatus`]); every cycle
//! that runs returns a finite command, see [`ldcbf_controller::mpc`] for the
//! fallbacks.
//!
//! ## No panics
//!
//! No function here panics: every pointer is checked for NULL and alignment
//! before use, slices are read with `get`, caller-given counts are bounded
//! before use. This is proved at link time together with the controller
//! under it: `nopanic/` links every function of this API, called with opaque
//! pointers and values, with `panic-never` (release build for Cortex-M7). With
//! the `std` feature (default; it links std, whose panic handler a host
//! `staticlib`/`cdylib` needs) a panic would in any case abort the process at
//! the `extern "C"` boundary rather than unwind into C.
#![no_std]
// The C boundary is unsafe by nature: raw pointers in, `#[no_mangle]` symbols
// out. Every `unsafe` block says why it is sound.
#![allow(unsafe_code)]
#![deny(
    clippy::undocumented_unsafe_blocks,
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]
#![warn(clippy::std_instead_of_core)]

#[cfg(feature = "std")]
extern crate std;

use core::ffi::{c_char, c_void};
use core::fmt::Write as _;
use core::mem::{align_of, size_of};
use core::ptr::{addr_of, addr_of_mut};

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    CommandSource, Config, ConfigError, ConvexPolygon, CycleInput, CycleOutput, CycleStatus,
    GeometryError, InputError, LipState, QpStatus, RobotController, Side,
};

/// Version of this C API; [`ldcbf_api_version`] returns it. Compare the two
/// to check that the header matches the library.
pub const LDCBF_API_VERSION: u32 = 1;

/// Horizon `N`: footsteps planned per cycle (the length of the plan arrays of
/// [`LdcbfPlan`]).
pub const LDCBF_HORIZON: usize = 3;

/// Obstacles used in one cycle's QP (the nearest ones within `r_active`; more
/// are allowed in the input, the farthest are then left out and
/// [`LdcbfCycleInfo::obstacles_truncated`] is set).
pub const LDCBF_MAX_ACTIVE_OBSTACLES: usize = 8;

/// Largest number of obstacles one [`ldcbf_step`] accepts.
pub const LDCBF_MAX_OBSTACLES: usize = 64;

/// Largest number of corners of an obstacle's convex hull.
pub const LDCBF_MAX_VERTICES: usize = 32;

/// Largest number of points one obstacle may be given as (its hull has at
/// most [`LDCBF_MAX_VERTICES`] corners). A larger count is rejected before
/// any point is read: a guard against garbage counts.
pub const LDCBF_MAX_POINTS: usize = 1024;

/// Bytes of storage a controller needs: at least `sizeof` the controller
/// (checked at compile time on every target the library is built for: x86-64,
/// aarch64 and thumbv7em in CI; [`ldcbf_controller_size`] gives the exact
/// figure of this build).
pub const LDCBF_CONTROLLER_SIZE: usize = 40_960;

/// Alignment, in bytes, the controller's storage needs (at least the
/// controller's alignment on every supported target;
/// [`ldcbf_controller_align`] gives the exact figure for this build).
pub const LDCBF_CONTROLLER_ALIGN: usize = 8;

/// [`LdcbfSide`] of the left foot.
pub const LDCBF_SIDE_LEFT: u32 = 0;
/// [`LdcbfSide`] of the right foot.
pub const LDCBF_SIDE_RIGHT: u32 = 1;

/// A foot: [`LDCBF_SIDE_LEFT`] (0) or [`LDCBF_SIDE_RIGHT`] (1); any other
/// value in an input is rejected with [`LdcbfResult::InvalidArgument`].
pub type LdcbfSide = u32;

/// Tag of an initialised controller ("LDCBFctl" in ASCII).
const MAGIC: u64 = 0x4c44_4342_4663_746c;

/// The controller: opaque to C, held in storage the caller provides (see
/// [`ldcbf_init`]). Holds the [`RobotController`] (model, factored Hessian,
/// warm-start memory, workspace), the buffer for one cycle's obstacles, and
/// the last error. It holds no pointer into itself or to the caller's
/// memory, so a byte copy of the storage (`memcpy` to another suitably
/// aligned buffer) is an independent controller in the same state. Not
/// thread-safe: one thread at a time may call functions on one controller;
/// different controllers are independent.
pub struct LdcbfController {
    magic: u64,
    controller: RobotController,
    obstacles: heapless::Vec<ConvexPolygon<LDCBF_MAX_VERTICES>, LDCBF_MAX_OBSTACLES, usize>,
    last_error: LastError,
}

const _: () = {
    assert!(size_of::<LdcbfController>() <= LDCBF_CONTROLLER_SIZE);
    assert!(align_of::<LdcbfController>() <= LDCBF_CONTROLLER_ALIGN);
    assert!(LDCBF_MAX_OBSTACLES <= u32::MAX as usize);
};

/// Result of a call: `Ok` or what the caller got wrong. Values are stable.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfResult {
    /// Success.
    Ok = 0,
    /// A required pointer argument is NULL.
    NullPointer = 1,
    /// A pointer argument is not aligned for its type (`double`: 8 bytes on
    /// most targets, `uint32_t`: 4, the controller: [`LDCBF_CONTROLLER_ALIGN`]).
    Misaligned = 2,
    /// The storage given to [`ldcbf_init`] is smaller than
    /// [`ldcbf_controller_size`] bytes.
    StorageTooSmall = 3,
    /// The controller pointer does not point to a controller set up by
    /// [`ldcbf_init`] (checked with a tag word: a best-effort guard against
    /// uninitialised or overwritten storage).
    NotInitialized = 4,
    /// An input or output buffer overlaps the controller's storage.
    Overlap = 5,
    /// The configuration is invalid; [`ldcbf_last_error`] names the field.
    InvalidConfig = 6,
    /// The controller has no valid configuration yet (from
    /// [`ldcbf_lip_propagate`]; [`ldcbf_step`] instead returns `Ok` with the
    /// hold command and [`LdcbfInputError::NotConfigured`], as the Rust
    /// controller does).
    NotConfigured = 7,
    /// A scalar argument is out of its range (a side that is neither 0 nor 1,
    /// a duration that is not finite); [`ldcbf_last_error`] names it.
    InvalidArgument = 8,
    /// More than [`LDCBF_MAX_OBSTACLES`] obstacles.
    TooManyObstacles = 9,
    /// An obstacle's points do not span a convex polygon of at most
    /// [`LDCBF_MAX_VERTICES`] corners (not finite, beyond 1e6 m, fewer than 3
    /// distinct points, collinear), or it has more than [`LDCBF_MAX_POINTS`]
    /// points; [`ldcbf_last_error`] says which and why.
    InvalidObstacle = 10,
}

/// Outcome of a control cycle (the Rust controller's `CycleStatus`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfCycleStatus {
    /// The QP was solved; the command is the optimal plan's first footstep.
    Optimal = 0,
    /// The QP had no feasible point; the command comes from the priority
    /// scheme (relaxed rows) or a fallback, see [`LdcbfCycleInfo::source`].
    Infeasible = 1,
    /// The iteration budget ran out; fallback command.
    BudgetExhausted = 2,
    /// The solver met a numerical failure; fallback command.
    NumericalFailure = 3,
    /// A measured input was not finite or out of range, or the controller is
    /// not configured ([`LdcbfOutput::input_error`] says which); the command
    /// holds the last valid target with turning rate 0.
    InvalidInput = 4,
}

/// Which input was invalid when the status is [`LdcbfCycleStatus::InvalidInput`].
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfInputError {
    /// No input error (the status is not `InvalidInput`).
    None = 0,
    /// CoM position, velocity, heading or turning rate not finite or out of
    /// range (positions within 1e6 m, speed within 100 m/s, turning rate
    /// within 100 rad/s).
    State = 1,
    /// Stance foot position not finite or out of range.
    StanceFoot = 2,
    /// Time in step not finite.
    TimeInStep = 3,
    /// Goal not finite or out of range.
    Goal = 4,
    /// The controller has no valid configuration ([`ldcbf_configure`] has not
    /// succeeded yet).
    NotConfigured = 5,
}

/// Where the command came from (the Rust controller's `CommandSource`).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfCommandSource {
    /// This cycle's optimal plan.
    Optimal = 0,
    /// Optimal plan with the gait rows relaxed (nominal QP infeasible).
    RelaxedGait = 1,
    /// Optimal plan with the safety (and gait) rows relaxed.
    RelaxedSafety = 2,
    /// The previous cycle's plan, still feasible for this cycle's rows.
    PreviousPlan = 3,
    /// The clamped capture step.
    CaptureStep = 4,
    /// Hold the last valid target (invalid input).
    Hold = 5,
}

/// Outcome of the QP solver in a cycle.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdcbfQpStatus {
    /// The QP was not built (invalid input).
    NotBuilt = 0,
    /// Solved to optimality.
    Solved = 1,
    /// The constraint set is empty.
    Infeasible = 2,
    /// The iteration budget ran out.
    IterationLimit = 3,
    /// A non-finite number appeared, or the Hessian was not positive definite.
    NumericalError = 4,
}

/// Controller settings (the Rust `Config`), SI units. Get the defaults (the
/// paper's Table I: a point robot, no foot rows) from
/// [`ldcbf_config_default`] and override fields. Flags are `uint8_t` and must
/// be 0 or 1; [`ldcbf_configure`] rejects anything else.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfConfig {
    /// Gravity `g`, m/s^2 (> 0).
    pub gravity: f64,
    /// CoM height `H`, m (> 0).
    pub com_height: f64,
    /// Step duration `T`, s (> 0).
    pub step_duration: f64,
    /// Minimum longitudinal (body x) velocity at the end of a step, m/s.
    pub vx_min: f64,
    /// Maximum longitudinal velocity, m/s (> `vx_min`).
    pub vx_max: f64,
    /// Minimum lateral velocity times the stance sign, m/s.
    pub vy_min: f64,
    /// Maximum lateral velocity times the stance sign, m/s (>= `vy_min`).
    pub vy_max: f64,
    /// Leg reachability half-width in each body axis, m (> 0).
    pub l_max: f64,
    /// Maneuverability coefficient `alpha`, m/rad (>= 0).
    pub alpha: f64,
    /// Turning-rate bound `omega_max`, rad/s (>= 0).
    pub omega_max: f64,
    /// LDCBF decay `gamma`, in (0, 1].
    pub gamma: f64,
    /// LDCBF margin `delta`, m (>= 0).
    pub delta: f64,
    /// Obstacles within this signed distance of the predicted CoM are active, m (> 0).
    pub r_active: f64,
    /// 1: foot-clearance rows on (every footprint keeps `foot_clearance` m
    /// off each active obstacle); 0: off (the paper's QP).
    pub foot_clearance_on: u8,
    /// Foot clearance `delta_foot`, m (finite; used when `foot_clearance_on`).
    pub foot_clearance: f64,
    /// Radius of the body disk around the CoM, m (>= 0; 0 = a point CoM).
    pub body_radius: f64,
    /// Footprint length along the heading, m (>= 0; 0 = a point foot).
    pub foot_length: f64,
    /// Footprint width across the heading, m (>= 0; 0 = a point foot).
    pub foot_width: f64,
    /// Within this distance of the goal the heading is frozen, m (>= 0).
    pub heading_freeze_radius: f64,
    /// Iteration budget of one QP solve (>= 1).
    pub max_iter: u32,
    /// Iteration budget of a whole cycle (>= `max_iter`).
    pub max_iter_cycle: u32,
    /// Halvings of each bisection of the priority scheme (<= 52).
    pub relax_bisections: u32,
    /// Largest uniform relaxation of the gait rows before the safety rows are
    /// relaxed instead, m/s (>= 0).
    pub max_gait_relaxation: f64,
    /// 1: capturability bound on (see `capture_fraction`); 0: off.
    pub capture_on: u8,
    /// Capturability bound as a fraction of `|kappa| l_max`, in (0, 1] (used
    /// when `capture_on`).
    pub capture_fraction: f64,
    /// 1: warm-start the solver with the previous cycle's active rows; 0: cold.
    pub warm_start: u8,
    /// Primal feasibility tolerance of the solver, in (0, 1e-3).
    pub tol_primal: f64,
}

/// The measured state and the goal of one cycle (world frame).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfInput {
    /// CoM position `{x, y}`, m.
    pub com_position: [f64; 2],
    /// CoM velocity `{vx, vy}`, m/s.
    pub com_velocity: [f64; 2],
    /// Heading (yaw), rad.
    pub heading: f64,
    /// Current turning rate (the last commanded one), rad/s.
    pub turning_rate: f64,
    /// Position of the current stance foot `{x, y}`, m.
    pub stance_foot: [f64; 2],
    /// Which foot is the stance foot: [`LDCBF_SIDE_LEFT`] or [`LDCBF_SIDE_RIGHT`].
    pub stance_side: LdcbfSide,
    /// Time already spent in the current step, s, in `[0, step_duration]`
    /// (clamped otherwise, and [`LdcbfCycleInfo::time_clamped`] set).
    pub time_in_step: f64,
    /// Goal (or current subgoal) `{x, y}`, m.
    pub goal: [f64; 2],
}

/// A LIP state (world frame).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct LdcbfLipState {
    /// CoM position `{x, y}`, m.
    pub position: [f64; 2],
    /// CoM velocity `{vx, vy}`, m/s.
    pub velocity: [f64; 2],
    /// Heading, rad.
    pub heading: f64,
}

/// The plan predicted in a cycle.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfPlan {
    /// `x_0`: predicted state at the end of the current step.
    pub x0: LdcbfLipState,
    /// `x_1 .. x_N`: predicted states at the ends of the planned steps.
    pub states: [LdcbfLipState; LDCBF_HORIZON],
    /// `f_0 .. f_{N-1}`: stance foot `{x, y}` of each planned step, m.
    pub feet: [[f64; 2]; LDCBF_HORIZON],
    /// Side of `f_0` (the current swing foot); later feet alternate.
    pub first_side: LdcbfSide,
}

/// Diagnostics of one cycle.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfCycleInfo {
    /// QP solver outcome ([`LdcbfQpStatus::NotBuilt`] on invalid input).
    pub qp_status: LdcbfQpStatus,
    /// Where the command came from.
    pub source: LdcbfCommandSource,
    /// Solver iterations (adds plus drops) of the whole cycle.
    pub iterations: u32,
    /// Size of the final active set.
    pub active_set_size: u32,
    /// Obstacles used in the QP (at most [`LDCBF_MAX_ACTIVE_OBSTACLES`]).
    pub active_obstacles: u32,
    /// 1 if more obstacles were within `r_active` than the QP holds (the
    /// farthest were left out), else 0.
    pub obstacles_truncated: u8,
    /// 1 if the predicted CoM `p_0` lies inside (or on) an obstacle, else 0.
    pub inside_obstacle: u8,
    /// 1 if `time_in_step` was outside `[0, T]` and was clamped, else 0.
    pub time_clamped: u8,
    /// 1 if warm-start rows were given to the solver, else 0.
    pub warm_started: u8,
    /// Cost `sum_k |p_k - goal|^2` of the returned plan, m^2 (NaN for `Hold`).
    pub cost: f64,
    /// Largest violation of this cycle's QP rows by the returned plan, in the
    /// rows' units (m or m/s; 0 when all hold; NaN for `Hold`).
    pub max_violation: f64,
    /// Smallest barrier value `h_j(p_0)` over the active obstacles, m
    /// (`+inf` without active obstacles).
    pub min_h0: f64,
    /// Uniform relaxation of the gait rows in the returned plan, m/s.
    pub relax_gait: f64,
    /// Uniform relaxation of the safety rows in the returned plan, m.
    pub relax_safety: f64,
    /// Uniform relaxation of the capturability bound, m/s.
    pub relax_capture: f64,
}

/// Everything one cycle returns. All command numbers are finite.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LdcbfOutput {
    /// `f_0`: where the current swing foot should land `{x, y}`, m (world).
    pub foot_target: [f64; 2],
    /// Turning rate to apply during the next step, rad/s.
    pub turning_rate: f64,
    /// Outcome of the cycle.
    pub status: LdcbfCycleStatus,
    /// Which input was invalid ([`LdcbfInputError::None`] unless `status` is
    /// [`LdcbfCycleStatus::InvalidInput`]).
    pub input_error: LdcbfInputError,
    /// The predicted plan.
    pub plan: LdcbfPlan,
    /// Diagnostics.
    pub info: LdcbfCycleInfo,
}

/// The last error recorded in a controller, for [`ldcbf_last_error`].
#[derive(Clone, Copy, Debug)]
enum LastError {
    None,
    Config(ConfigError),
    Flag(&'static str),
    Argument(&'static str),
    Pointer(&'static str),
    TooManyObstacles(u32),
    TooManyPoints(u32, u32),
    Obstacle(u32, GeometryError),
}

impl core::fmt::Display for LastError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LastError::None => f.write_str("no error"),
            LastError::Config(e) => write!(f, "{e}"),
            LastError::Flag(field) => {
                write!(f, "invalid controller setting `{field}`: must be 0 or 1")
            }
            LastError::Argument(what) => write!(f, "invalid argument: {what}"),
            LastError::Pointer(name) => write!(
                f,
                "pointer argument `{name}` is NULL, misaligned or overlaps the controller"
            ),
            LastError::TooManyObstacles(n) => write!(
                f,
                "{n} obstacles given, at most {LDCBF_MAX_OBSTACLES} (LDCBF_MAX_OBSTACLES) are accepted"
            ),
            LastError::TooManyPoints(i, n) => write!(
                f,
                "obstacle {i}: {n} points given, at most {LDCBF_MAX_POINTS} (LDCBF_MAX_POINTS) are accepted"
            ),
            LastError::Obstacle(i, e) => write!(f, "obstacle {i}: {e}"),
        }
    }
}

// ---------------------------------------------------------------------------
// Pointer checks

/// `Ok` if `p` is non-NULL and aligned for `T`.
fn check_ptr<T>(p: *const T) -> Result<(), LdcbfResult> {
    if p.is_null() {
        Err(LdcbfResult::NullPointer)
    } else if !p.is_aligned() {
        Err(LdcbfResult::Misaligned)
    } else {
        Ok(())
    }
}

/// Whether the byte ranges `[a, a + a_len)` and `[b, b + b_len)` intersect
/// (addresses only; lengths saturate).
fn overlaps(a: usize, a_len: usize, b: usize, b_len: usize) -> bool {
    a < b.saturating_add(b_len) && b < a.saturating_add(a_len) && a_len > 0 && b_len > 0
}

/// `Ok` if the `bytes` bytes at `p` do not overlap the controller at `ctl`.
fn check_disjoint<T>(
    p: *const T,
    bytes: usize,
    ctl: *const LdcbfController,
) -> Result<(), LdcbfResult> {
    if overlaps(
        p as usize,
        bytes,
        ctl as usize,
        size_of::<LdcbfController>(),
    ) {
        Err(LdcbfResult::Overlap)
    } else {
        Ok(())
    }
}

/// `Ok` if `ctl` is non-NULL, aligned and tagged by [`ldcbf_init`].
///
/// # Safety
/// If `ctl` is non-NULL and aligned it must be valid for reads of a
/// `LdcbfController` (the storage passed to [`ldcbf_init`]).
unsafe fn check_controller(ctl: *const LdcbfController) -> Result<(), LdcbfResult> {
    check_ptr(ctl)?;
    // SAFETY: `ctl` is non-NULL and aligned, and valid for reads by the
    // caller's contract; `magic` is a plain `u64` (any bits are a value), read
    // without forming a reference to the rest of the controller.
    let magic = unsafe { addr_of!((*ctl).magic).read_volatile() };
    if magic == MAGIC {
        Ok(())
    } else {
        Err(LdcbfResult::NotInitialized)
    }
}

/// A `u8` flag as a bool: 0 or 1, else the field's name.
fn flag(v: u8, field: &'static str) -> Result<bool, LastError> {
    match v {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(LastError::Flag(field)),
    }
}

/// A side code as a [`Side`].
fn side(v: LdcbfSide) -> Option<Side> {
    match v {
        LDCBF_SIDE_LEFT => Some(Side::Left),
        LDCBF_SIDE_RIGHT => Some(Side::Right),
        _ => None,
    }
}

fn side_code(s: Side) -> LdcbfSide {
    match s {
        Side::Left => LDCBF_SIDE_LEFT,
        Side::Right => LDCBF_SIDE_RIGHT,
    }
}

fn xy(v: [f64; 2]) -> Vector2<f64> {
    Vector2::new(v[0], v[1])
}

fn arr(v: &Vector2<f64>) -> [f64; 2] {
    [v.x, v.y]
}

// ---------------------------------------------------------------------------
// Conversions

impl From<&Config> for LdcbfConfig {
    fn from(c: &Config) -> Self {
        LdcbfConfig {
            gravity: c.gravity,
            com_height: c.com_height,
            step_duration: c.step_duration,
            vx_min: c.vx_min,
            vx_max: c.vx_max,
            vy_min: c.vy_min,
            vy_max: c.vy_max,
            l_max: c.l_max,
            alpha: c.alpha,
            omega_max: c.omega_max,
            gamma: c.gamma,
            delta: c.delta,
            r_active: c.r_active,
            foot_clearance_on: u8::from(c.foot_clearance.is_some()),
            foot_clearance: c.foot_clearance.unwrap_or(0.0),
            body_radius: c.body_radius,
            foot_length: c.foot_length,
            foot_width: c.foot_width,
            heading_freeze_radius: c.heading_freeze_radius,
            max_iter: c.max_iter,
            max_iter_cycle: c.max_iter_cycle,
            relax_bisections: c.relax_bisections,
            max_gait_relaxation: c.max_gait_relaxation,
            capture_on: u8::from(c.capture_fraction.is_some()),
            capture_fraction: c.capture_fraction.unwrap_or(0.0),
            warm_start: u8::from(c.warm_start),
            tol_primal: c.tol_primal,
        }
    }
}

impl LdcbfConfig {
    /// The Rust configuration, or the flag that is neither 0 nor 1 (the
    /// values are validated by `Controller::configure`).
    fn to_config(self) -> Result<Config, LastError> {
        let foot = flag(self.foot_clearance_on, "foot_clearance_on")?;
        let capture = flag(self.capture_on, "capture_on")?;
        let warm = flag(self.warm_start, "warm_start")?;
        Ok(Config {
            gravity: self.gravity,
            com_height: self.com_height,
            step_duration: self.step_duration,
            vx_min: self.vx_min,
            vx_max: self.vx_max,
            vy_min: self.vy_min,
            vy_max: self.vy_max,
            l_max: self.l_max,
            alpha: self.alpha,
            omega_max: self.omega_max,
            gamma: self.gamma,
            delta: self.delta,
            r_active: self.r_active,
            foot_clearance: foot.then_some(self.foot_clearance),
            body_radius: self.body_radius,
            foot_length: self.foot_length,
            foot_width: self.foot_width,
            heading_freeze_radius: self.heading_freeze_radius,
            max_iter: self.max_iter,
            max_iter_cycle: self.max_iter_cycle,
            relax_bisections: self.relax_bisections,
            max_gait_relaxation: self.max_gait_relaxation,
            capture_fraction: capture.then_some(self.capture_fraction),
            warm_start: warm,
            tol_primal: self.tol_primal,
        })
    }
}

impl From<&LipState> for LdcbfLipState {
    fn from(s: &LipState) -> Self {
        LdcbfLipState {
            position: arr(&s.position),
            velocity: arr(&s.velocity),
            heading: s.heading,
        }
    }
}

impl From<&CycleOutput<LDCBF_HORIZON>> for LdcbfOutput {
    fn from(o: &CycleOutput<LDCBF_HORIZON>) -> Self {
        let (status, input_error) = match o.status {
            CycleStatus::Optimal => (LdcbfCycleStatus::Optimal, LdcbfInputError::None),
            CycleStatus::Infeasible => (LdcbfCycleStatus::Infeasible, LdcbfInputError::None),
            CycleStatus::BudgetExhausted => {
                (LdcbfCycleStatus::BudgetExhausted, LdcbfInputError::None)
            }
            CycleStatus::NumericalFailure => {
                (LdcbfCycleStatus::NumericalFailure, LdcbfInputError::None)
            }
            CycleStatus::InvalidInput(e) => (
                LdcbfCycleStatus::InvalidInput,
                match e {
                    InputError::State => LdcbfInputError::State,
                    InputError::StanceFoot => LdcbfInputError::StanceFoot,
                    InputError::TimeInStep => LdcbfInputError::TimeInStep,
                    InputError::Goal => LdcbfInputError::Goal,
                    InputError::NotConfigured => LdcbfInputError::NotConfigured,
                },
            ),
        };
        let i = &o.info;
        LdcbfOutput {
            foot_target: arr(&o.foot_target),
            turning_rate: o.turning_rate,
            status,
            input_error,
            plan: LdcbfPlan {
                x0: (&o.plan.x0).into(),
                states: o.plan.states.map(|s| (&s).into()),
                feet: o.plan.feet.map(|f| arr(&f)),
                first_side: side_code(o.plan.first_side),
            },
            info: LdcbfCycleInfo {
                qp_status: match i.qp_status {
                    None => LdcbfQpStatus::NotBuilt,
                    Some(QpStatus::Solved) => LdcbfQpStatus::Solved,
                    Some(QpStatus::Infeasible) => LdcbfQpStatus::Infeasible,
                    Some(QpStatus::IterationLimit) => LdcbfQpStatus::IterationLimit,
                    Some(QpStatus::NumericalError) => LdcbfQpStatus::NumericalError,
                },
                source: match i.source {
                    CommandSource::Optimal => LdcbfCommandSource::Optimal,
                    CommandSource::RelaxedGait => LdcbfCommandSource::RelaxedGait,
                    CommandSource::RelaxedSafety => LdcbfCommandSource::RelaxedSafety,
                    CommandSource::PreviousPlan => LdcbfCommandSource::PreviousPlan,
                    CommandSource::CaptureStep => LdcbfCommandSource::CaptureStep,
                    CommandSource::Hold => LdcbfCommandSource::Hold,
                },
                iterations: i.iterations,
                active_set_size: u32::from(i.active_set_size),
                active_obstacles: u32::from(i.active_obstacles),
                obstacles_truncated: u8::from(i.obstacles_truncated),
                inside_obstacle: u8::from(i.inside_obstacle),
                time_clamped: u8::from(i.time_clamped),
                warm_started: u8::from(i.warm_started),
                cost: i.cost,
                max_violation: i.max_violation,
                min_h0: i.min_h0,
                relax_gait: i.relax_gait,
                relax_safety: i.relax_safety,
                relax_capture: i.relax_capture,
            },
        }
    }
}

// ---------------------------------------------------------------------------
// The C API

/// The API version of the library ([`LDCBF_API_VERSION`] when it was built).
#[unsafe(no_mangle)]
pub extern "C" fn ldcbf_api_version() -> u32 {
    LDCBF_API_VERSION
}

/// `sizeof` the controller in this build, bytes (at most [`LDCBF_CONTROLLER_SIZE`]).
#[unsafe(no_mangle)]
pub extern "C" fn ldcbf_controller_size() -> usize {
    size_of::<LdcbfController>()
}

/// Alignment of the controller in this build, bytes (at most
/// [`LDCBF_CONTROLLER_ALIGN`]).
#[unsafe(no_mangle)]
pub extern "C" fn ldcbf_controller_align() -> usize {
    align_of::<LdcbfController>()
}

/// Writes the default configuration (the paper's Table I: a point robot
/// without foot rows; horizon 3 budgets) to `*config`.
///
/// Returns [`LdcbfResult::NullPointer`] or [`LdcbfResult::Misaligned`] for a
/// bad `config`, else `Ok`.
///
/// # Safety
/// `config`, if non-NULL and aligned, must be valid for writes of an
/// [`LdcbfConfig`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ldcbf_config_default(config: *mut LdcbfConfig) -> LdcbfResult {
    if let Err(e) = check_ptr(config) {
        return e;
    }
    // SAFETY: non-NULL and aligned (checked), writable by the caller's contract.
    unsafe { config.write(LdcbfConfig::from(&Config::default())) };
    LdcbfResult::Ok
}

/// Sets up a controller, unconfigured, in the caller's `storage` of
/// `storage_size` bytes, and writes its handle (the same address as `storage`)
/// to `*out`. Allocates nothing. The storage must stay valid while the
/// controller is used; there is nothing to free. Calling it again on the same
/// storage starts over (unconfigured).
///
/// Until [`ldcbf_configure`] succeeds every [`ldcbf_step`] returns the hold
/// command with [`LdcbfInputError::NotConfigured`].
///
/// Returns [`LdcbfResult::NullPointer`] / [`LdcbfResult::Misaligned`] for a
/// bad `storage` (needs [`LDCBF_CONTROLLER_ALIGN`]) or `out`,
/// [`LdcbfResult::StorageTooSmall`] if `storage_size <`
/// [`ldcbf_controller_size`], [`LdcbfResult::Overlap`] if `out` lies in the
/// storage, else `Ok`.
///
/// # Safety
/// `storage` must be valid for writes of `storage_size` bytes and not be used
/// for anything else while the controller lives; `out`, if non-NULL and
/// aligned, must be valid for a write of a pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ldcbf_init(
    storage: *mut c_void,
    storage_size: usize,
    out: *mut *mut LdcbfController,
) -> LdcbfResult {
    let ctl = storage.cast::<LdcbfController>();
    if let Err(e) = check_ptr(ctl).and(check_ptr(out)) {
        return e;
    }
    if storage_size < size_of::<LdcbfController>() {
        return LdcbfResult::StorageTooSmall;
    }
    if let Err(e) = check_disjoint(out, size_of::<*mut LdcbfController>(), ctl) {
        return e;
    }
    // SAFETY: `ctl` is non-NULL, aligned and valid for writes of
    // `size_of::<LdcbfController>()` bytes (checked size, caller's contract).
    // Each field is written in place through a raw pointer, without reading
    // the uninitialised storage; the tag goes last.
    unsafe {
        addr_of_mut!((*ctl).controller).write(RobotController::UNCONFIGURED);
        addr_of_mut!((*ctl).obstacles).write(heapless::Vec::new());
        addr_of_mut!((*ctl).last_error).write(LastError::None);
        addr_of_mut!((*ctl).magic).write(MAGIC);
        out.write(ctl);
    }
    LdcbfResult::Ok
}

/// Validates `*config`, precomputes the model and the Hessian factorisation
/// and configures the controller in place. On success the warm-start and
/// fallback memory are cleared. On error the controller is unchanged (an
/// unconfigured one stays unconfigured, a configured one keeps its
/// configuration) and [`ldcbf_last_error`] names the bad field.
///
/// Returns `Ok`, [`LdcbfResult::InvalidConfig`], or a pointer error
/// (`NullPointer`, `Misaligned`, `NotInitialized`, `Overlap`).
///
/// # Safety
/// `ctl` must point to storage set up by [`ldcbf_init`] (or be NULL);
/// `config`, if non-NULL and aligned, must be valid for reads of an
/// [`LdcbfConfig`]. No other thread may use the controller during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ldcbf_configure(
    ctl: *mut LdcbfController,
    config: *const LdcbfConfig,
) -> LdcbfResult {
    // SAFETY: the caller's contract on `ctl`.
    if let Err(e) = unsafe { check_controller(ctl) } {
        return e;
    }
    if let Err(e) = check_ptr(config).and(check_disjoint(config, size_of::<LdcbfConfig>(), ctl)) {
        // SAFETY: a tagged controller, exclusively ours for the call.
        unsafe { (*ctl).last_error = LastError::Pointer("config") };
        return e;
    }
    // SAFETY: non-NULL, aligned, readable by contract; `LdcbfConfig` is plain
    // data (any bits of its `f64`/`u32`/`u8` fields are values).
    let config = unsafe { config.read() };
    // SAFETY: `ctl` is a tagged controller (checked) and the caller gives us
    // exclusive use of it; `config` was copied out, so nothing aliases it.
    let ctl = unsafe { &mut *ctl };
    let result = config
        .to_config()
        .and_then(|c| ctl.controller.configure(c).map_err(LastError::Config));
    match result {
        Ok(()) => LdcbfResult::Ok,
        Err(e) => {
            ctl.last_error = e;
            LdcbfResult::InvalidConfig
        }
    }
}

/// Forgets the warm-start and fallback memory (e.g. after the robot was
/// stopped or moved by hand); the configuration stays.
///
/// Returns `Ok` or a pointer error (`NullPointer`, `Misaligned`, `NotInitialized`).
///
/// # Safety
/// As [`ldcbf_configure`] for `ctl`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ldcbf_reset(ctl: *mut LdcbfController) -> LdcbfResult {
    // SAFETY: the caller's contract on `ctl`.
    if let Err(e) = unsafe { check_controller(ctl) } {
        return e;
    }
    // SAFETY: a tagged controller, exclusively ours for the call.
    unsafe { (*ctl).controller.reset() };
    LdcbfResult::Ok
}

/// One control cycle: predicts, plans the headings, selects the obstacles,
/// solves the QP and writes the command and diagnostics to `*out`.
///
/// Obstacles are given as plain arrays: obstacle `i` (`0 <= i < n_obstacles`)
/// is the convex hull of the next `point_counts[i]` points of `points`, which
/// holds `{x0, y0, x1, y1, ...}` (m, world) for all obstacles one after the
/// other (`2 * sum(point_counts)` doubles). Any point set whose hull has 3 to
/// [`LDCBF_MAX_VERTICES`] corners is accepted (a convex polygon's vertices in
/// either order, or the raw points of a cluster). With `n_obstacles == 0` both
/// pointers may be NULL.
///
/// Returns `Ok` when the controller ran (whatever the cycle's status: see
/// `out->status`; a measurement that is NaN or out of range gives
/// [`LdcbfCycleStatus::InvalidInput`] and the hold command, as in Rust).
/// Otherwise `*out` is not written, the controller's warm-start and
/// fallback memory are unchanged, and the result says why: a pointer error (`NullPointer`, `Misaligned`,
/// `NotInitialized`, `Overlap`), [`LdcbfResult::InvalidArgument`] (stance side
/// neither 0 nor 1), [`LdcbfResult::TooManyObstacles`],
/// [`LdcbfResult::InvalidObstacle`] (an invalid obstacle, or more than
/// [`LDCBF_MAX_POINTS`] points for one; [`ldcbf_last_error`] names it).
///
/// # Safety
/// As [`ldcbf_configure`] for `ctl`; `input` and `out`, if non-NULL and
/// aligned, must be valid for a read of an [`LdcbfInput`] and a write of an
/// [`LdcbfOutput`]; `point_counts` must be valid for reads of `n_obstacles`
/// `uint32_t` and `points` of `2 * sum(point_counts)` doubles (when
/// non-NULL and aligned).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ldcbf_step(
    ctl: *mut LdcbfController,
    input: *const LdcbfInput,
    points: *const f64,
    point_counts: *const u32,
    n_obstacles: u32,
    out: *mut LdcbfOutput,
) -> LdcbfResult {
    // SAFETY: the caller's contract on `ctl`.
    if let Err(e) = unsafe { check_controller(ctl) } {
        return e;
    }
    let pointers = [
        (
            "input",
            check_ptr(input).and(check_disjoint(input, size_of::<LdcbfInput>(), ctl)),
        ),
        (
            "out",
            check_ptr(out).and(check_disjoint(out, size_of::<LdcbfOutput>(), ctl)),
        ),
    ];
    for (name, check) in pointers {
        if let Err(e) = check {
            // SAFETY: a tagged controller, exclusively ours for the call.
            unsafe { (*ctl).last_error = LastError::Pointer(name) };
            return e;
        }
    }
    // SAFETY: non-NULL, aligned, readable by contract; plain data except
    // `stance_side`, a `u32` checked below.
    let input = unsafe { input.read() };
    let (counts, pts) = match unsafe {
        // SAFETY: forwarded contract on `points` and `point_counts`.
        obstacle_slices(ctl, points, point_counts, n_obstacles)
    } {
        Ok(s) => s,
        Err((result, error)) => {
            // SAFETY: a tagged controller, exclusively ours; no reference to
            // it is alive (the slices were not made).
            unsafe { (*ctl).last_error = error };
            return result;
        }
    };
    // SAFETY: a tagged controller, exclusively ours for the call; the caller's
    // slices `counts` and `pts` lie outside it (checked), so they do not alias.
    let handle = unsafe { &mut *ctl };
    let Some(stance_side) = side(input.stance_side) else {
        handle.last_error = LastError::Argument("stance_side must be 0 (left) or 1 (right)");
        return LdcbfResult::InvalidArgument;
    };
    if let Err(e) = load_obstacles(&mut handle.obstacles, counts, pts) {
        handle.last_error = e;
        return LdcbfResult::InvalidObstacle;
    }
    let cycle = CycleInput {
        com_position: xy(input.com_position),
        com_velocity: xy(input.com_velocity),
        heading: input.heading,
        turning_rate: input.turning_rate,
        stance_foot: xy(input.stance_foot),
        stance_side,
        time_in_step: input.time_in_step,
        goal: xy(input.goal),
        obstacles: &handle.obstacles,
    };
    let result = handle.controller.step(&cycle);
    // SAFETY: non-NULL, aligned, writable by contract, outside the controller.
    unsafe { out.write(LdcbfOutput::from(&result)) };
    LdcbfResult::Ok
}

/// The point count of each obstacle and all their points `{x, y}`.
type ObstacleSlices<'a> = (&'a [u32], &'a [[f64; 2]]);

/// The caller's obstacle arrays as slices: `n` point counts and the points
/// they add up to, checked for NULL, alignment, size and overlap with the
/// controller.
///
/// # Safety
/// As [`ldcbf_step`] for `points` and `counts`.
unsafe fn obstacle_slices<'a>(
    ctl: *const LdcbfController,
    points: *const f64,
    counts: *const u32,
    n: u32,
) -> Result<ObstacleSlices<'a>, (LdcbfResult, LastError)> {
    if n == 0 {
        return Ok((&[], &[]));
    }
    let bad = |r: LdcbfResult, what: &'static str| (r, LastError::Pointer(what));
    if usize::try_from(n).map_or(true, |n| n > LDCBF_MAX_OBSTACLES) {
        return Err((
            LdcbfResult::TooManyObstacles,
            LastError::TooManyObstacles(n),
        ));
    }
    let n = n as usize; // <= LDCBF_MAX_OBSTACLES, checked above
    check_ptr(counts)
        .and(check_disjoint(
            counts,
            n.saturating_mul(size_of::<u32>()),
            ctl,
        ))
        .map_err(|r| bad(r, "point_counts"))?;
    // SAFETY: non-NULL, aligned, readable for `n` values by contract, at most
    // `LDCBF_MAX_OBSTACLES * 4` bytes, outside the controller.
    let counts = unsafe { core::slice::from_raw_parts(counts, n) };
    let mut total = 0usize;
    for (i, &c) in (0u32..).zip(counts) {
        if c as usize > LDCBF_MAX_POINTS {
            return Err((LdcbfResult::InvalidObstacle, LastError::TooManyPoints(i, c)));
        }
        // At most LDCBF_MAX_OBSTACLES * LDCBF_MAX_POINTS: cannot overflow.
        total = total.saturating_add(c as usize);
    }
    if total == 0 {
        // Every obstacle is empty: reported by `load_obstacles`.
        return Ok((counts, &[]));
    }
    let pts = points.cast::<[f64; 2]>();
    check_ptr(pts)
        .and(check_disjoint(
            pts,
            total.saturating_mul(size_of::<[f64; 2]>()),
            ctl,
        ))
        .map_err(|r| bad(r, "points"))?;
    // SAFETY: non-NULL, aligned (`[f64; 2]` has the alignment of `f64`),
    // readable for `2 * total` doubles by contract, at most
    // `LDCBF_MAX_OBSTACLES * LDCBF_MAX_POINTS * 16` bytes (1 MiB), outside the
    // controller.
    let pts = unsafe { core::slice::from_raw_parts(pts, total) };
    Ok((counts, pts))
}

/// Validates the obstacles (convex hulls) into `buf`.
fn load_obstacles(
    buf: &mut heapless::Vec<ConvexPolygon<LDCBF_MAX_VERTICES>, LDCBF_MAX_OBSTACLES, usize>,
    counts: &[u32],
    mut pts: &[[f64; 2]],
) -> Result<(), LastError> {
    buf.clear();
    for (i, &c) in (0u32..).zip(counts) {
        // `pts` holds exactly the sum of the counts (`obstacle_slices`).
        let Some((these, rest)) = pts.split_at_checked(c as usize) else {
            return Err(LastError::TooManyPoints(i, c));
        };
        pts = rest;
        let poly = ConvexPolygon::hull(these).map_err(|e| LastError::Obstacle(i, e))?;
        if buf.push(poly).is_err() {
            return Err(LastError::TooManyObstacles(i));
        }
    }
    Ok(())
}

/// The LIP's closed-form flow under the controller's model: from CoM position
/// `p[2]` (m) and velocity `v[2]` (m/s) over `tau` seconds with the stance
/// foot at `foot[2]` (m), writes the new position to `p_out[2]` and velocity
/// to `v_out[2]` (world frame). For plants and tests that must integrate
/// exactly as the controller predicts (the C example closes its loop with it).
///
/// Returns `Ok`, [`LdcbfResult::NotConfigured`], [`LdcbfResult::InvalidArgument`]
/// (`tau` not finite), or a pointer error.
///
/// # Safety
/// As [`ldcbf_configure`] for `ctl` (read only); `p`, `v`, `foot` must be
/// valid for reads and `p_out`, `v_out` for writes of 2 doubles each (when
/// non-NULL and aligned).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ldcbf_lip_propagate(
    ctl: *const LdcbfController,
    p: *const f64,
    v: *const f64,
    foot: *const f64,
    tau: f64,
    p_out: *mut f64,
    v_out: *mut f64,
) -> LdcbfResult {
    // SAFETY: the caller's contract on `ctl`.
    if let Err(e) = unsafe { check_controller(ctl) } {
        return e;
    }
    let two = size_of::<[f64; 2]>();
    let ins = [p, v, foot].map(|q| q.cast::<[f64; 2]>());
    let outs = [p_out, v_out].map(|q| q.cast::<[f64; 2]>());
    for q in ins.into_iter().chain(outs.map(<*mut [f64; 2]>::cast_const)) {
        if let Err(e) = check_ptr(q).and(check_disjoint(q, two, ctl)) {
            return e;
        }
    }
    // SAFETY: a tagged controller, only read here.
    let handle = unsafe { &*ctl };
    if !handle.controller.is_configured() {
        return LdcbfResult::NotConfigured;
    }
    if !tau.is_finite() {
        return LdcbfResult::InvalidArgument;
    }
    let [p, v, foot] = ins;
    // SAFETY: non-NULL, aligned, readable for 2 doubles by contract.
    let (p, v, foot) = unsafe { (p.read(), v.read(), foot.read()) };
    let (p1, v1) = handle
        .controller
        .lip()
        .propagate(&xy(p), &xy(v), &xy(foot), tau);
    let [p_out, v_out] = outs;
    // SAFETY: non-NULL, aligned, writable for 2 doubles by contract (outputs
    // may alias the inputs: these were copied out above).
    unsafe {
        p_out.write(arr(&p1));
        v_out.write(arr(&v1));
    }
    LdcbfResult::Ok
}

/// Writes a description of the controller's last error (from
/// [`ldcbf_configure`] or [`ldcbf_step`]; "no error" if none), NUL-terminated
/// and truncated to fit, to `buf[0 .. buf_len]`, like `snprintf`. Returns the
/// length of the whole message without the NUL (so a return value `>=
/// buf_len` means it was truncated), or 0 if `ctl` is not a valid controller
/// or `buf` is NULL with a non-zero `buf_len`.
///
/// # Safety
/// As [`ldcbf_configure`] for `ctl` (read only); `buf`, if non-NULL, must be
/// valid for writes of `buf_len` bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn ldcbf_last_error(
    ctl: *const LdcbfController,
    buf: *mut c_char,
    buf_len: usize,
) -> usize {
    // SAFETY: the caller's contract on `ctl`.
    if unsafe { check_controller(ctl) }.is_err() {
        return 0;
    }
    // SAFETY: a tagged controller; the error is copied out, no reference kept.
    let error = unsafe { (*ctl).last_error };
    let mut sink: &mut [u8] = &mut [];
    if buf_len > 0 {
        if buf.is_null()
            || buf_len > isize::MAX as usize
            || overlaps(
                buf as usize,
                buf_len,
                ctl as usize,
                size_of::<LdcbfController>(),
            )
        {
            return 0;
        }
        // SAFETY: non-NULL, writable for `buf_len` bytes by contract (bytes
        // have alignment 1), at most `isize::MAX`, outside the controller.
        sink = unsafe { core::slice::from_raw_parts_mut(buf.cast::<u8>(), buf_len) };
    }
    let mut w = Truncating { buf: sink, len: 0 };
    // `Truncating` never fails and the `Display` impls only write.
    let _ = write!(w, "{error}");
    let Truncating { buf, len } = w;
    if let Some(last) = buf.len().checked_sub(1)
        && let Some(nul) = buf.get_mut(len.min(last))
    {
        *nul = 0;
    }
    len
}

/// A `fmt::Write` into a byte buffer that keeps the last byte for a NUL,
/// drops what does not fit and counts everything.
struct Truncating<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl core::fmt::Write for Truncating<'_> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        let room = self.buf.len().saturating_sub(1);
        for &b in s.as_bytes() {
            if self.len < room
                && let Some(slot) = self.buf.get_mut(self.len)
            {
                *slot = b;
            }
            self.len = self.len.saturating_add(1);
        }
        Ok(())
    }
}

/// Name of an [`LdcbfResult`] value as a static NUL-terminated string
/// (`"ok"`, `"null_pointer"`, ...; `"unknown"` for any other value).
#[unsafe(no_mangle)]
pub extern "C" fn ldcbf_result_name(result: u32) -> *const c_char {
    let s: &'static core::ffi::CStr = match result {
        0 => c"ok",
        1 => c"null_pointer",
        2 => c"misaligned",
        3 => c"storage_too_small",
        4 => c"not_initialized",
        5 => c"overlap",
        6 => c"invalid_config",
        7 => c"not_configured",
        8 => c"invalid_argument",
        9 => c"too_many_obstacles",
        10 => c"invalid_obstacle",
        _ => c"unknown",
    };
    s.as_ptr()
}

/// Name of an [`LdcbfCycleStatus`] value as a static NUL-terminated string
/// (`"optimal"`, `"infeasible"`, `"budget_exhausted"`, `"numerical_failure"`,
/// `"invalid_input"`, the Rust controller's names; `"unknown"` otherwise).
#[unsafe(no_mangle)]
pub extern "C" fn ldcbf_cycle_status_name(status: u32) -> *const c_char {
    let s: &'static core::ffi::CStr = match status {
        0 => c"optimal",
        1 => c"infeasible",
        2 => c"budget_exhausted",
        3 => c"numerical_failure",
        4 => c"invalid_input",
        _ => c"unknown",
    };
    s.as_ptr()
}

#[cfg(test)]
mod tests;
