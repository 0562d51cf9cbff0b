//! The C API called from Rust as C would call it: results of every bad
//! pointer and argument, nothing written on error, configuration round trip,
//! and cycles equal to the Rust controller's (with a body and foot rows, which
//! the C example does not use).
#![allow(
    clippy::undocumented_unsafe_blocks,
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

extern crate std;

use core::ffi::CStr;
use std::boxed::Box;
use std::format;
use std::string::String;
use std::vec::Vec;

use core::ptr::{null, null_mut};

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{CommandSource, CycleOutput, CycleStatus, InputError, LipState, Side};
use ldcbf_nav::fixtures::{open_loop_walk, robot_config};

use super::types::side_code;
use super::*;

/// Caller storage for one controller, as C would declare it.
#[repr(C, align(8))]
struct Storage([u8; LDCBF_CONTROLLER_SIZE]);

fn storage() -> Box<Storage> {
    Box::new(Storage([0xA5; LDCBF_CONTROLLER_SIZE]))
}

/// A controller initialised in `s`.
fn init(s: &mut Storage) -> *mut LdcbfController {
    let mut ctl = null_mut();
    let r = unsafe { ldcbf_init(s.0.as_mut_ptr().cast(), s.0.len(), &mut ctl) };
    assert_eq!(r, LdcbfResult::Ok);
    assert_eq!(ctl.cast::<u8>(), s.0.as_mut_ptr());
    ctl
}

fn default_config() -> LdcbfConfig {
    let mut c = core::mem::MaybeUninit::<LdcbfConfig>::uninit();
    assert_eq!(
        unsafe { ldcbf_config_default(c.as_mut_ptr()) },
        LdcbfResult::Ok
    );
    unsafe { c.assume_init() }
}

/// A configured controller in `s`.
fn configured(s: &mut Storage, cfg: &LdcbfConfig) -> *mut LdcbfController {
    let ctl = init(s);
    assert_eq!(unsafe { ldcbf_configure(ctl, cfg) }, LdcbfResult::Ok);
    ctl
}

fn last_error(ctl: *const LdcbfController) -> String {
    let mut buf = [0 as c_char; 256];
    let n = unsafe { ldcbf_last_error(ctl, buf.as_mut_ptr(), buf.len()) };
    let s = unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_str()
        .unwrap()
        .into();
    assert_eq!(n, String::len(&s), "message fits: length returned");
    s
}

fn input_at_rest() -> LdcbfInput {
    LdcbfInput {
        com_position: [0.0, 0.0],
        com_velocity: [0.0, 0.0],
        heading: 0.0,
        turning_rate: 0.0,
        stance_foot: [0.0, 0.0],
        stance_side: LDCBF_SIDE_LEFT,
        time_in_step: 0.0,
        goal: [10.0, 10.0],
    }
}

/// An output filled with a sentinel, to see whether a call wrote it.
fn sentinel() -> LdcbfOutput {
    let mut o = LdcbfOutput::from(&CycleOutput::<LDCBF_HORIZON> {
        foot_target: Vector2::new(-7.0, -7.0),
        turning_rate: -7.0,
        plan: ldcbf_controller::Plan {
            x0: LipState::default(),
            states: [LipState::default(); LDCBF_HORIZON],
            feet: [Vector2::zeros(); LDCBF_HORIZON],
            first_side: Side::Left,
        },
        status: CycleStatus::Optimal,
        info: ldcbf_controller::CycleInfo {
            qp_status: None,
            iterations: 777,
            active_set_size: 0,
            active_obstacles: 0,
            obstacles_truncated: false,
            inside_obstacle: false,
            time_clamped: false,
            warm_started: false,
            source: CommandSource::Optimal,
            cost: 0.0,
            max_violation: 0.0,
            min_h0: 0.0,
            relax_gait: 0.0,
            relax_safety: 0.0,
            relax_capture: 0.0,
        },
    });
    o.info.iterations = 777;
    o
}

/// A triangle and a square (points, counts).
fn two_obstacles() -> (Vec<f64>, Vec<u32>) {
    (
        std::vec![
            2.0, 1.0, 3.0, 1.0, 2.5, 2.0, // triangle
            1.0, 3.0, 2.0, 3.0, 2.0, 4.0, 1.0, 4.0, // square
        ],
        std::vec![3, 4],
    )
}

fn step(
    ctl: *mut LdcbfController,
    input: &LdcbfInput,
    points: &[f64],
    counts: &[u32],
    out: &mut LdcbfOutput,
) -> LdcbfResult {
    let n = u32::try_from(counts.len()).unwrap();
    unsafe { ldcbf_step(ctl, input, points.as_ptr(), counts.as_ptr(), n, out) }
}

#[test]
fn sizes_fit_the_exported_constants() {
    assert!(ldcbf_controller_size() <= LDCBF_CONTROLLER_SIZE);
    assert!(LDCBF_CONTROLLER_ALIGN.is_multiple_of(ldcbf_controller_align()));
    assert_eq!(ldcbf_api_version(), LDCBF_API_VERSION);
    // The exported capacities are the controller's.
    let c = RobotController::new(Config::default()).unwrap();
    assert_eq!(
        c.last_assembly().obstacles.len(),
        LDCBF_MAX_ACTIVE_OBSTACLES
    );
    assert_eq!(
        c.last_assembly().prediction.heading.theta.len(),
        LDCBF_HORIZON
    );
}

#[test]
fn a_byte_copy_is_an_independent_controller_in_the_same_state() {
    let mut a = storage();
    let ctl_a = configured(&mut a, &default_config());
    let (points, counts) = two_obstacles();
    let mut input = input_at_rest();
    input.goal = [4.0, 5.0];
    let mut out_a = sentinel();
    let mut out_b = sentinel();
    for i in 0..5 {
        input.time_in_step = f64::from(i) * 0.05;
        assert_eq!(
            step(ctl_a, &input, &points, &counts, &mut out_a),
            LdcbfResult::Ok
        );
    }
    let mut b = storage();
    b.0.copy_from_slice(&a.0);
    let ctl_b = b.0.as_mut_ptr().cast::<LdcbfController>();
    drop(a); // the copy does not depend on the original
    let mut c = storage();
    let ctl_c = configured(&mut c, &default_config());
    for i in 0..5 {
        input.time_in_step = f64::from(i) * 0.05;
        assert_eq!(
            step(ctl_c, &input, &points, &counts, &mut out_a),
            LdcbfResult::Ok
        );
    }
    for i in 5..8 {
        input.time_in_step = f64::from(i) * 0.05;
        assert_eq!(
            step(ctl_b, &input, &points, &counts, &mut out_b),
            LdcbfResult::Ok
        );
        assert_eq!(
            step(ctl_c, &input, &points, &counts, &mut out_a),
            LdcbfResult::Ok
        );
        assert_eq!(format!("{out_a:?}"), format!("{out_b:?}"), "cycle {i}");
    }
}

#[test]
fn default_config_round_trips_to_the_rust_default() {
    let c = default_config();
    assert_eq!(c.to_config().unwrap(), Config::default());
    assert_eq!(c.foot_clearance_on, 0);
    assert_eq!(c.capture_on, 1);
    // And a configuration with every option set.
    let rust = Config {
        foot_clearance: Some(0.02),
        capture_fraction: None,
        warm_start: false,
        body_radius: 0.25,
        foot_length: 0.22,
        foot_width: 0.10,
        turn_vertex_normals: true,
        velocity_margin: false,
        person_speed_max: 1.2,
        person_accel_max: 0.5,
        person_reach_time: 1.2,
        ..Config::default()
    };
    assert_eq!(LdcbfConfig::from(&rust).to_config().unwrap(), rust);
}

#[test]
fn init_checks_storage_and_out_pointer() {
    let mut s = storage();
    let base = s.0.as_mut_ptr();
    let size = s.0.len();
    let mut ctl = null_mut();
    unsafe {
        assert_eq!(
            ldcbf_init(null_mut(), size, &mut ctl),
            LdcbfResult::NullPointer
        );
        assert_eq!(
            ldcbf_init(base.cast(), size, null_mut()),
            LdcbfResult::NullPointer
        );
        assert_eq!(
            ldcbf_init(base.add(4).cast(), size - 4, &mut ctl),
            LdcbfResult::Misaligned
        );
        assert_eq!(
            ldcbf_init(base.cast(), ldcbf_controller_size() - 1, &mut ctl),
            LdcbfResult::StorageTooSmall
        );
        // `out` inside the storage.
        assert_eq!(
            ldcbf_init(base.cast(), size, base.add(64).cast()),
            LdcbfResult::Overlap
        );
        assert!(ctl.is_null(), "nothing written on error");
        // Exactly the exact size is enough.
        assert_eq!(
            ldcbf_init(base.cast(), ldcbf_controller_size(), &mut ctl),
            LdcbfResult::Ok
        );
    }
    assert_eq!(ctl.cast::<u8>(), base);
}

#[test]
fn calls_on_bad_handles_are_rejected() {
    let mut s = storage(); // never initialised: 0xA5 bytes
    let raw = s.0.as_mut_ptr().cast::<LdcbfController>();
    let cfg = default_config();
    let input = input_at_rest();
    let mut out = sentinel();
    let p = [0.0; 2];
    let mut q = [0.0; 2];
    let mut q2 = [0.0; 2];
    unsafe {
        for (ctl, expected) in [
            (null_mut(), LdcbfResult::NullPointer),
            (
                s.0.as_mut_ptr().add(1).cast::<LdcbfController>(),
                LdcbfResult::Misaligned,
            ),
            (raw, LdcbfResult::NotInitialized),
        ] {
            assert_eq!(ldcbf_configure(ctl, &cfg), expected);
            assert_eq!(ldcbf_reset(ctl), expected);
            assert_eq!(
                ldcbf_step(ctl, &input, null(), null(), 0, &mut out),
                expected
            );
            assert_eq!(
                ldcbf_lip_propagate(
                    ctl,
                    p.as_ptr(),
                    p.as_ptr(),
                    p.as_ptr(),
                    0.1,
                    q.as_mut_ptr(),
                    q2.as_mut_ptr()
                ),
                expected
            );
            let mut buf = [1 as c_char; 8];
            assert_eq!(ldcbf_last_error(ctl, buf.as_mut_ptr(), buf.len()), 0);
            assert_eq!(buf, [1; 8], "nothing written");
        }
    }
    assert_eq!(format!("{out:?}"), format!("{:?}", sentinel()));
}

#[test]
fn configure_rejects_bad_values_and_flags_naming_the_field() {
    let mut s = storage();
    let ctl = init(&mut s);
    assert_eq!(last_error(ctl), "no error");
    let mut cfg = default_config();
    cfg.gravity = -9.81;
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &cfg) },
        LdcbfResult::InvalidConfig
    );
    assert!(last_error(ctl).contains("`gravity`"), "{}", last_error(ctl));
    let mut cfg = default_config();
    cfg.warm_start = 2;
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &cfg) },
        LdcbfResult::InvalidConfig
    );
    assert!(last_error(ctl).contains("`warm_start`: must be 0 or 1"));
    let mut cfg = default_config();
    cfg.foot_clearance_on = 1;
    cfg.foot_clearance = f64::NAN;
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &cfg) },
        LdcbfResult::InvalidConfig
    );
    assert!(last_error(ctl).contains("`foot_clearance`"));
    assert_eq!(
        unsafe { ldcbf_configure(ctl, null()) },
        LdcbfResult::NullPointer
    );
    assert!(last_error(ctl).contains("`config`"));
    // Still unconfigured: a step holds and says so.
    let mut out = sentinel();
    assert_eq!(
        step(ctl, &input_at_rest(), &[], &[], &mut out),
        LdcbfResult::Ok
    );
    assert_eq!(out.status, LdcbfCycleStatus::InvalidInput);
    assert_eq!(out.input_error, LdcbfInputError::NotConfigured);
    assert_eq!(out.info.source, LdcbfCommandSource::Hold);
    assert_eq!(out.info.qp_status, LdcbfQpStatus::NotBuilt);
    assert_eq!(out.foot_target, [0.0, 0.0], "holds the stance foot");
    assert_eq!(out.turning_rate, 0.0);
    // A valid configuration then works, and a bad one later keeps it.
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &default_config()) },
        LdcbfResult::Ok
    );
    let mut bad = default_config();
    bad.gamma = 1.5;
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &bad) },
        LdcbfResult::InvalidConfig
    );
    assert_eq!(
        step(ctl, &input_at_rest(), &[], &[], &mut out),
        LdcbfResult::Ok
    );
    assert_eq!(out.status, LdcbfCycleStatus::Optimal);
}

#[test]
fn step_rejects_bad_arguments_and_writes_nothing() {
    let mut s = storage();
    let ctl = configured(&mut s, &default_config());
    let (points, counts) = two_obstacles();
    let input = input_at_rest();
    let mut out = sentinel();
    let untouched = format!("{:?}", sentinel());
    unsafe {
        // NULL input or output.
        assert_eq!(
            ldcbf_step(ctl, null(), null(), null(), 0, &mut out),
            LdcbfResult::NullPointer
        );
        assert_eq!(
            ldcbf_step(ctl, &input, null(), null(), 0, null_mut()),
            LdcbfResult::NullPointer
        );
        assert!(last_error(ctl).contains("`out`"));
        // Misaligned input.
        let mut bytes = std::vec![0u8; size_of::<LdcbfInput>() + 8];
        let at = bytes.as_mut_ptr().add(1 + bytes.as_ptr().align_offset(8));
        let mis = at.cast::<LdcbfInput>();
        assert_eq!(
            ldcbf_step(ctl, mis, null(), null(), 0, &mut out),
            LdcbfResult::Misaligned
        );
        // Output inside the controller's storage.
        let inside = s.0.as_mut_ptr().add(1024).cast::<LdcbfOutput>();
        assert_eq!(
            ldcbf_step(ctl, &input, null(), null(), 0, inside),
            LdcbfResult::Overlap
        );
        // Obstacles: NULL counts or points, misaligned points, too many.
        assert_eq!(
            ldcbf_step(ctl, &input, points.as_ptr(), null(), 2, &mut out),
            LdcbfResult::NullPointer
        );
        assert_eq!(
            ldcbf_step(ctl, &input, null(), counts.as_ptr(), 2, &mut out),
            LdcbfResult::NullPointer
        );
        assert!(last_error(ctl).contains("`points`"));
        let shifted = points.as_ptr().cast::<u8>().add(4).cast::<f64>();
        assert_eq!(
            ldcbf_step(ctl, &input, shifted, counts.as_ptr(), 2, &mut out),
            LdcbfResult::Misaligned
        );
        assert_eq!(
            ldcbf_step(ctl, &input, points.as_ptr(), counts.as_ptr(), 65, &mut out),
            LdcbfResult::TooManyObstacles
        );
        assert!(last_error(ctl).contains("65 obstacles"));
    }
    // A garbage count is refused before any point is read.
    let huge = [3, u32::MAX];
    assert_eq!(
        step(ctl, &input, &points, &huge, &mut out),
        LdcbfResult::InvalidObstacle
    );
    assert!(last_error(ctl).contains("obstacle 1: 4294967295 points"));
    // Stance side neither 0 nor 1.
    let mut bad = input;
    bad.stance_side = 2;
    assert_eq!(
        step(ctl, &bad, &points, &counts, &mut out),
        LdcbfResult::InvalidArgument
    );
    assert!(last_error(ctl).contains("stance_side"));
    // Invalid obstacles: collinear, too few points, not finite.
    for (pts, cnt, why) in [
        (
            std::vec![0.0, 0.0, 1.0, 1.0, 2.0, 2.0],
            std::vec![3],
            "collinear",
        ),
        (std::vec![0.0, 0.0, 1.0, 1.0], std::vec![2], "fewer than 3"),
        (
            std::vec![0.0, 0.0, 1.0, f64::NAN, 2.0, 0.0],
            std::vec![3],
            "not finite",
        ),
        (std::vec![], std::vec![0], "fewer than 3"),
    ] {
        assert_eq!(
            step(ctl, &input, &pts, &cnt, &mut out),
            LdcbfResult::InvalidObstacle,
            "{why}"
        );
        let msg = last_error(ctl);
        assert!(
            msg.starts_with("obstacle 0: ") && msg.contains(why),
            "{msg}"
        );
    }
    assert_eq!(format!("{out:?}"), untouched, "nothing was written");
}

#[test]
fn invalid_measurements_give_the_hold_command() {
    let mut s = storage();
    let ctl = configured(&mut s, &default_config());
    let mut out = sentinel();
    let mut input = input_at_rest();
    input.stance_foot = [0.5, 0.25];
    input.com_velocity = [f64::NAN, 0.0];
    assert_eq!(step(ctl, &input, &[], &[], &mut out), LdcbfResult::Ok);
    assert_eq!(out.status, LdcbfCycleStatus::InvalidInput);
    assert_eq!(out.input_error, LdcbfInputError::State);
    assert_eq!(out.foot_target, [0.5, 0.25]);
    let mut input = input_at_rest();
    input.goal = [f64::INFINITY, 0.0];
    assert_eq!(step(ctl, &input, &[], &[], &mut out), LdcbfResult::Ok);
    assert_eq!(out.input_error, LdcbfInputError::Goal);
    assert_eq!(
        name(ldcbf_cycle_status_name(out.status as u32)),
        "invalid_input"
    );
}

/// A static name returned by the API.
fn name(p: *const c_char) -> &'static str {
    assert!(!p.is_null());
    unsafe { CStr::from_ptr(p) }.to_str().unwrap()
}

#[test]
fn names_cover_every_value() {
    let results = [
        (LdcbfResult::Ok, "ok"),
        (LdcbfResult::NullPointer, "null_pointer"),
        (LdcbfResult::Misaligned, "misaligned"),
        (LdcbfResult::StorageTooSmall, "storage_too_small"),
        (LdcbfResult::NotInitialized, "not_initialized"),
        (LdcbfResult::Overlap, "overlap"),
        (LdcbfResult::InvalidConfig, "invalid_config"),
        (LdcbfResult::NotConfigured, "not_configured"),
        (LdcbfResult::InvalidArgument, "invalid_argument"),
        (LdcbfResult::TooManyObstacles, "too_many_obstacles"),
        (LdcbfResult::InvalidObstacle, "invalid_obstacle"),
    ];
    for (r, expected) in results {
        assert_eq!(name(ldcbf_result_name(r as u32)), expected);
    }
    assert_eq!(name(ldcbf_result_name(results.len() as u32)), "unknown");
    for s in [
        CycleStatus::Optimal,
        CycleStatus::Infeasible,
        CycleStatus::BudgetExhausted,
        CycleStatus::NumericalFailure,
        CycleStatus::InvalidInput(InputError::Goal),
    ] {
        let code = LdcbfOutput::from(&CycleOutput {
            status: s,
            ..sentinel_rust()
        })
        .status;
        assert_eq!(name(ldcbf_cycle_status_name(code as u32)), s.name());
    }
    assert_eq!(name(ldcbf_cycle_status_name(5)), "unknown");
}

/// A Rust output to vary one field of.
fn sentinel_rust() -> CycleOutput<LDCBF_HORIZON> {
    let mut c = RobotController::new(Config::default()).unwrap();
    let obstacles: [ConvexPolygon<LDCBF_MAX_VERTICES>; 0] = [];
    c.step(
        &ldcbf_controller::RecordedInput::at_rest(Vector2::new(1.0, 0.0)).input(&obstacles),
        None,
    )
}

#[test]
fn last_error_truncates_like_snprintf() {
    let mut s = storage();
    let ctl = init(&mut s);
    let mut cfg = default_config();
    cfg.tol_primal = 1.0;
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &cfg) },
        LdcbfResult::InvalidConfig
    );
    let full = last_error(ctl);
    assert_eq!(
        full,
        "invalid controller setting `tol_primal`: must be in (0, 1e-3)"
    );
    // Length only.
    assert_eq!(unsafe { ldcbf_last_error(ctl, null_mut(), 0) }, full.len());
    // NULL with a length: refused.
    assert_eq!(unsafe { ldcbf_last_error(ctl, null_mut(), 8) }, 0);
    // Truncated, NUL-terminated.
    let mut buf = [1 as c_char; 11];
    let n = unsafe { ldcbf_last_error(ctl, buf.as_mut_ptr(), buf.len()) };
    assert_eq!(n, full.len());
    let got = unsafe { CStr::from_ptr(buf.as_ptr()) }.to_str().unwrap();
    assert_eq!(got, &full[..10]);
    // A one-byte buffer holds just the NUL.
    let mut one = [1 as c_char; 1];
    assert_eq!(
        unsafe { ldcbf_last_error(ctl, one.as_mut_ptr(), 1) },
        full.len()
    );
    assert_eq!(one, [0]);
}

#[test]
fn lip_propagate_is_the_controllers_model() {
    let mut s = storage();
    let ctl = init(&mut s);
    let (p, v, f) = ([0.1, -0.2], [0.3, 0.05], [0.0, 0.1]);
    let (mut p1, mut v1) = ([0.0; 2], [0.0; 2]);
    let call = |tau: f64, p1: &mut [f64; 2], v1: &mut [f64; 2]| unsafe {
        ldcbf_lip_propagate(
            ctl,
            p.as_ptr(),
            v.as_ptr(),
            f.as_ptr(),
            tau,
            p1.as_mut_ptr(),
            v1.as_mut_ptr(),
        )
    };
    assert_eq!(call(0.05, &mut p1, &mut v1), LdcbfResult::NotConfigured);
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &default_config()) },
        LdcbfResult::Ok
    );
    assert_eq!(
        call(f64::NAN, &mut p1, &mut v1),
        LdcbfResult::InvalidArgument
    );
    assert_eq!(call(0.05, &mut p1, &mut v1), LdcbfResult::Ok);
    let rust = RobotController::new(Config::default()).unwrap();
    let (rp, rv) = rust.lip().propagate(&xy(p), &xy(v), &xy(f), 0.05);
    assert_eq!((p1, v1), (arr(&rp), arr(&rv)));
    assert_ne!(p1, p, "it moved");
}

/// A robot with a body and feet (the simulator's `[robot]` defaults, foot
/// rows on): 200 cycles of an open-loop walk toward a goal behind two
/// obstacles, through the C API and through the Rust controller directly, give
/// the same outputs (every field; the command bit for bit), also across a reset.
#[test]
fn robot_config_cycles_equal_the_rust_controller() {
    robot_cycles_equal_rust(&[]);
}

/// As [`robot_config_cycles_equal_the_rust_controller`] with both obstacles
/// moving (`ldcbf_step_moving`): the triangle towards the walk, the square
/// across it.
#[test]
fn moving_obstacle_cycles_equal_the_rust_controller() {
    robot_cycles_equal_rust(&[Vector2::new(-0.3, -0.2), Vector2::new(0.25, -0.1)]);
}

/// The walk of [`robot_config_cycles_equal_the_rust_controller`] with the
/// obstacles' `velocities` (empty: `ldcbf_step`, at rest).
fn robot_cycles_equal_rust(velocities: &[Vector2<f64>]) {
    let rust_cfg = robot_config();
    let mut s = storage();
    let ctl = configured(&mut s, &LdcbfConfig::from(&rust_cfg));
    let mut rust = RobotController::new(rust_cfg).unwrap();
    let (points, counts) = two_obstacles();
    let xy_points: Vec<[f64; 2]> = points.chunks(2).map(|c| [c[0], c[1]]).collect();
    let (triangle, square) = xy_points.split_at(3);
    let polys: [ConvexPolygon<LDCBF_MAX_VERTICES>; 2] = [
        ConvexPolygon::hull(triangle).unwrap(),
        ConvexPolygon::hull(square).unwrap(),
    ];
    let mut out = sentinel();
    let (mut optimal, mut moving) = (0, 0);
    for i in 0..200u32 {
        let input = open_loop_walk(i).input_moving(&polys, velocities);
        let side = input.stance_side;
        if i == 100 {
            assert_eq!(unsafe { ldcbf_reset(ctl) }, LdcbfResult::Ok);
            rust.reset();
        }
        let expected = rust.step(&input, None);
        let c_input = LdcbfInput {
            com_position: arr(&input.com_position),
            com_velocity: arr(&input.com_velocity),
            heading: input.heading,
            turning_rate: input.turning_rate,
            stance_foot: arr(&input.stance_foot),
            stance_side: side_code(side),
            time_in_step: input.time_in_step,
            goal: arr(&input.goal),
        };
        let flat: Vec<f64> = velocities.iter().flat_map(|v| [v.x, v.y]).collect();
        let result = if velocities.is_empty() {
            step(ctl, &c_input, &points, &counts, &mut out)
        } else {
            unsafe {
                ldcbf_step_moving(
                    ctl,
                    &c_input,
                    points.as_ptr(),
                    counts.as_ptr(),
                    2,
                    flat.as_ptr(),
                    &mut out,
                )
            }
        };
        assert_eq!(result, LdcbfResult::Ok);
        assert_eq!(
            format!("{out:?}"),
            format!("{:?}", LdcbfOutput::from(&expected)),
            "cycle {i}"
        );
        assert_eq!(
            out.foot_target[0].to_bits(),
            expected.foot_target.x.to_bits()
        );
        optimal += usize::from(out.status == LdcbfCycleStatus::Optimal);
        let asm = rust.last_assembly();
        moving += usize::from(
            asm.obstacles[..asm.n_obstacles]
                .iter()
                .any(|o| o.half_plane.rate != 0.0),
        );
    }
    assert!(optimal > 100, "{optimal} optimal cycles");
    assert_eq!(moving > 100, !velocities.is_empty(), "{moving} cycles");
}

/// `ldcbf_step_moving`: NULL velocities are `ldcbf_step`; a misaligned or
/// overlapping array is a pointer error that writes nothing; a NaN velocity
/// is the controller's input error with the hold command.
#[test]
fn step_moving_checks_the_velocities() {
    let mut s = storage();
    let ctl = configured(&mut s, &default_config());
    let (points, counts) = two_obstacles();
    let mut input = input_at_rest();
    input.goal = [3.0, 3.0];
    input.com_position = [1.0, 1.5];
    input.stance_foot = [1.0, 1.5];
    let mut out = sentinel();
    let untouched = format!("{:?}", sentinel());
    let call = |v: *const f64, out: &mut LdcbfOutput| unsafe {
        ldcbf_step_moving(ctl, &input, points.as_ptr(), counts.as_ptr(), 2, v, out)
    };
    let velocities = [0.1, 0.0, f64::NAN, 0.0, 0.0];
    let misaligned = velocities
        .as_ptr()
        .cast::<u8>()
        .wrapping_add(1)
        .cast::<f64>();
    assert_eq!(call(misaligned, &mut out), LdcbfResult::Misaligned);
    assert_eq!(format!("{out:?}"), untouched);
    assert!(
        last_error(ctl).contains("`velocities`"),
        "{}",
        last_error(ctl)
    );
    assert_eq!(call(ctl.cast::<f64>(), &mut out), LdcbfResult::Overlap);
    assert_eq!(format!("{out:?}"), untouched);
    assert_eq!(call(velocities.as_ptr(), &mut out), LdcbfResult::Ok);
    assert_eq!(out.status, LdcbfCycleStatus::InvalidInput);
    assert_eq!(out.input_error, LdcbfInputError::ObstacleVelocity);
    let mut at_rest = sentinel();
    let mut null_v = sentinel();
    assert_eq!(
        step(ctl, &input, &points, &counts, &mut at_rest),
        LdcbfResult::Ok
    );
    assert_eq!(unsafe { ldcbf_reset(ctl) }, LdcbfResult::Ok);
    assert_eq!(call(null(), &mut null_v), LdcbfResult::Ok);
    assert_eq!(format!("{at_rest:?}"), format!("{null_v:?}"));
}

/// `ldcbf_step_uncertain`: NULL radii are `ldcbf_step_moving`; a misaligned
/// or overlapping array is a pointer error that writes nothing; a NaN or
/// negative radius is the controller's input error with the hold command,
/// and a positive one is the Rust controller's cycle, bit for bit.
#[test]
fn step_uncertain_checks_the_radii() {
    let mut s = storage();
    let ctl = configured(&mut s, &default_config());
    let (points, counts) = two_obstacles();
    let mut input = input_at_rest();
    input.goal = [3.0, 3.0];
    input.com_position = [1.0, 1.5];
    input.stance_foot = [1.0, 1.5];
    let mut out = sentinel();
    let untouched = format!("{:?}", sentinel());
    let velocities = [0.1, 0.0, 0.0, 0.0];
    let call = |r: *const f64, out: &mut LdcbfOutput| unsafe {
        ldcbf_reset(ctl);
        ldcbf_step_uncertain(
            ctl,
            &input,
            points.as_ptr(),
            counts.as_ptr(),
            2,
            velocities.as_ptr(),
            r,
            out,
        )
    };
    let radii = [0.3, 0.0, f64::NAN];
    let misaligned = radii.as_ptr().cast::<u8>().wrapping_add(1).cast::<f64>();
    assert_eq!(call(misaligned, &mut out), LdcbfResult::Misaligned);
    assert_eq!(format!("{out:?}"), untouched);
    assert!(last_error(ctl).contains("`radii`"), "{}", last_error(ctl));
    assert_eq!(call(ctl.cast::<f64>(), &mut out), LdcbfResult::Overlap);
    assert_eq!(format!("{out:?}"), untouched);
    for bad in [[f64::NAN, 0.0], [-0.1, 0.0], [f64::INFINITY, 0.0]] {
        assert_eq!(call(bad.as_ptr(), &mut out), LdcbfResult::Ok);
        assert_eq!(out.status, LdcbfCycleStatus::InvalidInput);
        assert_eq!(out.input_error, LdcbfInputError::ObstacleVelocityRadius);
    }
    // NULL radii: `ldcbf_step_moving`.
    let mut moving = sentinel();
    let mut null_r = sentinel();
    assert_eq!(unsafe { ldcbf_reset(ctl) }, LdcbfResult::Ok);
    let r = unsafe {
        ldcbf_step_moving(
            ctl,
            &input,
            points.as_ptr(),
            counts.as_ptr(),
            2,
            velocities.as_ptr(),
            &mut moving,
        )
    };
    assert_eq!(r, LdcbfResult::Ok);
    assert_eq!(call(null(), &mut null_r), LdcbfResult::Ok);
    assert_eq!(format!("{moving:?}"), format!("{null_r:?}"));
    // A radius: the Rust controller's cycle.
    let mut c_out = sentinel();
    assert_eq!(call(radii.as_ptr(), &mut c_out), LdcbfResult::Ok);
    let obstacles: Vec<ConvexPolygon<LDCBF_MAX_VERTICES>> = [(0, 3), (3, 4)]
        .iter()
        .map(|&(at, n)| {
            let pts: Vec<[f64; 2]> = (at..at + n)
                .map(|i| [points[2 * i], points[2 * i + 1]])
                .collect();
            ConvexPolygon::hull(&pts).unwrap()
        })
        .collect();
    let v = [Vector2::new(0.1, 0.0), Vector2::zeros()];
    let mut rust = RobotController::new(Config::default()).unwrap();
    let rust_out = rust.step(
        &CycleInput {
            com_position: Vector2::new(1.0, 1.5),
            com_velocity: Vector2::zeros(),
            heading: input.heading,
            turning_rate: input.turning_rate,
            stance_foot: Vector2::new(1.0, 1.5),
            stance_side: ldcbf_controller::Side::Left,
            time_in_step: input.time_in_step,
            goal: Vector2::new(3.0, 3.0),
            obstacles: &obstacles,
            obstacle_velocities: &v,
            obstacle_velocity_radii: &radii[..2],
            speed_cap: ldcbf_controller::NO_SPEED_CAP,
        },
        None,
    );
    assert_eq!(
        format!("{c_out:?}"),
        format!("{:?}", LdcbfOutput::from(&rust_out))
    );
    assert_ne!(format!("{c_out:?}"), format!("{moving:?}"));
}

mod hostile;
