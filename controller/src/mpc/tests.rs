use super::cycle::output_is_finite;
use super::*;
use crate::constraints::RowKind;
use crate::geometry::ConvexPolygon;
use crate::qp::{DenseQp, QpStatus};
use crate::relax;

/// `Config::FIELDS` is the struct's field list, in order (read off its
/// derived `Debug`, which names every field).
#[test]
fn config_fields_are_the_struct_fields() {
    extern crate std;
    use std::string::String;
    use std::vec::Vec;
    let dbg = std::format!("{:?}", Config::default());
    let body = dbg.trim_start_matches("Config {").trim_end_matches('}');
    let names: Vec<String> = body
        .split(", ")
        .filter_map(|kv| kv.split_once(": ").map(|(k, _)| String::from(k.trim())))
        .filter(|k| k.chars().all(|c| c.is_ascii_lowercase() || c == '_'))
        .collect();
    assert_eq!(names, Config::FIELDS.to_vec());
}

type Ctl = PaperController;
type Poly = ConvexPolygon<16>;

fn input<'a>(obstacles: &'a [Poly]) -> CycleInput<'a, 16> {
    CycleInput {
        com_position: Vector2::new(0.0, 0.0),
        com_velocity: Vector2::new(0.0, 0.0),
        heading: 0.0,
        turning_rate: 0.0,
        stance_foot: Vector2::new(0.0, -0.05),
        stance_side: Side::Left,
        time_in_step: 0.0,
        goal: Vector2::new(5.0, 0.0),
        obstacles,
        obstacle_velocities: &[],
        obstacle_velocity_radii: &[],
        speed_cap: crate::NO_SPEED_CAP,
    }
}

#[test]
fn default_config_is_valid_and_bad_fields_are_named() {
    assert!(Config::default().validate().is_ok());
    let c = Config {
        vx_max: -1.0,
        ..Config::default()
    };
    assert_eq!(c.validate().unwrap_err().field, "vx_max");
    let c = Config {
        gamma: 0.0,
        ..Config::default()
    };
    assert_eq!(c.validate().unwrap_err().field, "gamma");
    let c = Config {
        com_height: f64::NAN,
        ..Config::default()
    };
    assert_eq!(c.validate().unwrap_err().field, "com_height");
    let c = Config {
        foot_clearance: Some(0.1),
        ..Config::default()
    };
    assert_eq!(Ctl::new(c).unwrap_err().field, "foot_clearance");
    assert!(Controller::<3, 6, { constraint_capacity(3, 8, true) }, 8>::new(c).is_ok());
    // Valid fields whose step map cannot be inverted for the foot.
    for t in [1e-6, 1e3] {
        let c = Config {
            step_duration: t,
            ..Config::default()
        };
        assert!(c.validate().is_ok());
        assert_eq!(Ctl::new(c).unwrap_err().field, "step_duration", "T = {t}");
    }
    let c = Config {
        step_duration: 1e-3,
        ..Config::default()
    };
    assert!(Ctl::new(c).is_ok());
}

#[test]
fn unconfigured_controller_holds_until_configured_in_place() {
    let mut ctl = Ctl::UNCONFIGURED;
    assert!(!ctl.is_configured());
    let wall = [Poly::new(&[[0.6, -2.0], [1.6, -2.0], [1.6, 2.0], [0.6, 2.0]]).unwrap()];
    let inp = input(&wall);
    let not_configured = CycleStatus::InvalidInput(InputError::NotConfigured);
    let out = ctl.step(&inp, None);
    assert_eq!(out.status, not_configured);
    assert_eq!(out.info.source, CommandSource::Hold);
    assert_eq!(out.foot_target, inp.stance_foot);
    assert_eq!(out.turning_rate, 0.0);
    assert!(output_is_finite(&out));
    let mut bad_foot = inp;
    bad_foot.stance_foot.x = f64::NAN;
    let out = ctl.step(&bad_foot, None);
    assert_eq!(out.status, not_configured);
    assert_eq!(out.foot_target, Vector2::zeros());
    assert!(output_is_finite(&out));
    let mut asm = Assembly::default();
    assert_eq!(
        ctl.assemble(&inp, None, &mut asm),
        Err(InputError::NotConfigured)
    );
    // A failed configure leaves it unconfigured.
    let bad = Config {
        gamma: 0.0,
        ..Config::default()
    };
    assert_eq!(ctl.configure(bad).unwrap_err().field, "gamma");
    let t = Config {
        step_duration: 1e-6,
        ..Config::default()
    };
    assert_eq!(ctl.configure(t).unwrap_err().field, "step_duration");
    assert!(!ctl.is_configured());
    assert_eq!(ctl.step(&inp, None).status, not_configured);
    // Configured in place it behaves as `new`, cycle after cycle (the
    // warm-start memory included).
    ctl.configure(Config::default()).unwrap();
    assert!(ctl.is_configured());
    let mut fresh = Ctl::new(Config::default()).unwrap();
    let walk = |ctl: &mut Ctl, fresh: &mut Ctl| {
        let mut i = inp;
        for k in 0..6 {
            i.time_in_step = 0.1 * f64::from(k % 4);
            i.com_velocity = Vector2::new(0.3 + 0.1 * f64::from(k), 0.05);
            let (a, b) = (ctl.step(&i, None), fresh.step(&i, None));
            assert_eq!(a, b, "cycle {k}");
            assert_ne!(a.status, not_configured);
        }
    };
    walk(&mut ctl, &mut fresh);
    // A failed reconfiguration changes nothing (configuration and memory).
    let mut twin = ctl.clone();
    assert!(ctl.configure(bad).is_err());
    assert!(ctl.is_configured());
    assert_eq!(ctl.config(), &Config::default());
    walk(&mut ctl, &mut twin);
    // A successful one clears the memory: as new again.
    let cfg = Config {
        delta: 0.1,
        ..Config::default()
    };
    ctl.configure(cfg).unwrap();
    let mut fresh = Ctl::new(cfg).unwrap();
    assert_eq!(ctl.config(), fresh.config());
    walk(&mut ctl, &mut fresh);
}

#[test]
fn free_walk_is_optimal_and_feasible() {
    let mut ctl = Ctl::new(Config::default()).unwrap();
    let out = ctl.step(&input(&[]), None);
    assert_eq!(out.status, CycleStatus::Optimal);
    assert_eq!(out.info.source, CommandSource::Optimal);
    assert!(out.info.max_violation <= 1e-9);
    assert_eq!(out.plan.first_side, Side::Right);
    // Walking towards +x: the plan moves forward.
    assert!(out.plan.states[2].position.x > 0.0);
}

#[test]
fn obstacles_are_selected_nearest_first_and_truncated() {
    let mut obs = [Poly::new(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]).unwrap(); 10];
    for (i, o) in obs.iter_mut().enumerate() {
        let x = 1.0 + 0.3 * (9 - i) as f64;
        *o = Poly::new(&[[x, 1.0], [x + 0.2, 1.0], [x + 0.1, 1.2]]).unwrap();
    }
    let ctl = Ctl::new(Config::default()).unwrap();
    let mut asm = Assembly::default();
    ctl.assemble(&input(&obs), None, &mut asm).unwrap();
    assert_eq!(asm.n_obstacles, 8);
    assert!(asm.obstacles_truncated);
    assert_eq!(asm.obstacles[0].index, 9);
    for w in asm.obstacles[..8].windows(2) {
        assert!(w[0].distance <= w[1].distance);
    }
    assert_eq!(asm.qp.m, 8 * 3 + 8 * 3);
    assert_eq!(asm.rows[24].kind, RowKind::Ldcbf(9));
}

#[test]
fn prediction_uses_remaining_time_and_current_turn_rate() {
    let ctl = Ctl::new(Config::default()).unwrap();
    let mut inp = input(&[]);
    inp.com_velocity = Vector2::new(0.3, -0.1);
    inp.heading = 3.1;
    inp.turning_rate = 0.2;
    inp.time_in_step = 0.1;
    let mut asm = Assembly::default();
    ctl.assemble(&inp, None, &mut asm).unwrap();
    let lip = Lip::new(9.81, 1.0, 0.4);
    let (px, vx) = lip.propagate_axis(0.0, 0.3, 0.0, 0.3);
    let (py, vy) = lip.propagate_axis(0.0, -0.1, -0.05, 0.3);
    let pr = &asm.prediction;
    assert!((pr.p0 - Vector2::new(px, py)).amax() < 1e-15);
    assert!((pr.v0 - Vector2::new(vx, vy)).amax() < 1e-15);
    // 3.1 + 0.2 * 0.3 = 3.16 > pi: wrapped.
    assert!((pr.heading.theta[0] - (3.16 - 2.0 * core::f64::consts::PI)).abs() < 1e-12);
    assert_eq!(pr.first_side, Side::Right);
    // Out-of-range time is clamped and flagged.
    inp.time_in_step = 0.5;
    ctl.assemble(&inp, None, &mut asm).unwrap();
    assert!(asm.time_clamped);
    assert!((asm.prediction.v0 - Vector2::new(0.3, -0.1)).amax() < 1e-15);
}

#[test]
fn warm_start_follows_the_horizon_shift() {
    let mut ctl = Ctl::new(Config::default()).unwrap();
    let first = ctl.step(&input(&[]), None);
    assert!(first.status.is_optimal());
    let n_active = ctl.memory.n_active;
    assert!(n_active > 0);
    // Same step: same rows are preferred.
    let again = ctl.step(&input(&[]), None);
    assert!(again.info.warm_started);
    // The step ended: stance switches, rows of k = 0 are dropped and k >= 1
    // move to k - 1; the plan is still the same optimum as a cold solve.
    let mut next = input(&[]);
    next.stance_side = Side::Right;
    next.stance_foot = first.foot_target;
    let warm = ctl.step(&next, None);
    let mut cold_ctl = Ctl::new(Config::default()).unwrap();
    let cold = cold_ctl.step(&next, None);
    assert!((warm.foot_target - cold.foot_target).amax() < 1e-9);
    assert_eq!(warm.status, cold.status);
}

/// Largest violation (physical units) of the rows of `class` by the plan
/// of `out`, on the QP of the last step.
fn class_violation(ctl: &Ctl, out: &CycleOutput<3>, class: relax::RowClass) -> f64 {
    let asm = ctl.last_assembly();
    relax::class_violation(&asm.qp, &asm.rows, &ctl.variables_of(&out.plan)).of(class)
}

/// Feasibility of the last QP with the rows of `class` relaxed by `eps` and
/// the rows of `drop` left out.
fn feasible_with(
    ctl: &Ctl,
    class: relax::RowClass,
    eps: f64,
    drop: Option<relax::RowClass>,
) -> bool {
    let asm = ctl.last_assembly();
    let mut qp = DenseQp::<6, 48>::with_q(asm.qp.q);
    for i in 0..asm.qp.m {
        let c = relax::RowClass::of(asm.rows[i].kind);
        if Some(c) == drop {
            continue;
        }
        let g = asm.qp.row(i);
        let h = asm.qp.h[i] + if c == class { eps } else { 0.0 };
        qp.push_row(&g, h).unwrap();
    }
    ctl.solver()
        .with_max_iter(500)
        .solve(&qp, &[false; 48])
        .status
        == QpStatus::Solved
}

#[test]
fn velocity_conflict_relaxes_gait_rows_minimally() {
    let mut ctl = Ctl::new(Config::default()).unwrap();
    let mut inp = input(&[]);
    // Sideways at 1.2 m/s towards the stance side: no reachable foot brings the
    // lateral velocity into [0.1, 0.4] at the end of the next step.
    inp.com_velocity = Vector2::new(0.0, -1.2);
    let out = ctl.step(&inp, None);
    assert_eq!(out.status, CycleStatus::Infeasible);
    assert_eq!(out.info.source, CommandSource::RelaxedGait);
    let eps = out.info.relax_gait;
    assert!(eps > 0.0);
    assert_eq!(out.info.relax_safety, 0.0);
    assert!(class_violation(&ctl, &out, relax::RowClass::Reach) <= 1e-9);
    assert!(class_violation(&ctl, &out, relax::RowClass::Gait) <= eps * (1.0 + 1e-9) + 1e-9);
    // Minimal: 1% less relaxation is infeasible, the reported one is feasible.
    assert!(!feasible_with(
        &ctl,
        relax::RowClass::Gait,
        0.99 * eps,
        None
    ));
    assert!(feasible_with(&ctl, relax::RowClass::Gait, eps, None));
    assert!(output_is_finite(&out));
    assert_eq!(
        out.turning_rate,
        ctl.last_assembly().prediction.heading.omega_bar
    );
}

#[test]
fn wall_ahead_inside_margin_relaxes_safety_but_keeps_reach() {
    let cfg = Config {
        delta: 0.3,
        ..Config::default()
    };
    let mut ctl = Ctl::new(cfg).unwrap();
    // A wall 0.05 m ahead of x_0, robot walking into it at 0.8 m/s.
    let wall = [Poly::new(&[[0.0, -2.0], [1.0, -2.0], [1.0, 2.0], [0.0, 2.0]]).unwrap()];
    let mut inp = input(&wall);
    inp.time_in_step = 0.4;
    inp.com_position = Vector2::new(-0.05, 0.0);
    inp.stance_foot = Vector2::new(-0.05, -0.05);
    inp.com_velocity = Vector2::new(0.8, 0.0);
    let out = ctl.step(&inp, None);
    assert_eq!(out.status, CycleStatus::Infeasible);
    assert_eq!(out.info.source, CommandSource::RelaxedSafety);
    assert!(out.info.relax_safety > 0.0);
    assert!(class_violation(&ctl, &out, relax::RowClass::Reach) <= 1e-9);
    let eps = out.info.relax_safety;
    assert!(class_violation(&ctl, &out, relax::RowClass::Safety) <= eps * (1.0 + 1e-9) + 1e-9);
    assert!(!feasible_with(
        &ctl,
        relax::RowClass::Safety,
        0.99 * eps,
        Some(relax::RowClass::Gait)
    ));
    assert!(output_is_finite(&out));
}

#[test]
fn exhausted_cycle_budget_falls_back() {
    // The nominal solve of this cycle needs a few iterations to prove
    // infeasibility; the relaxation then has (almost) nothing left.
    let cfg = Config {
        max_iter: 12,
        max_iter_cycle: 12,
        ..Config::default()
    };
    let mut ctl = Ctl::new(cfg).unwrap();
    let mut inp = input(&[]);
    inp.com_velocity = Vector2::new(0.0, -1.2);
    let out = ctl.step(&inp, None);
    assert_eq!(out.status, CycleStatus::Infeasible);
    assert_eq!(out.info.source, CommandSource::CaptureStep);
    assert!(out.info.iterations <= 64);
    assert!(class_violation(&ctl, &out, relax::RowClass::Reach) <= 1e-9);
}

#[test]
fn fallback_prefers_the_candidate_that_keeps_safety() {
    let wall = [Poly::new(&[[0.6, -2.0], [1.6, -2.0], [1.6, 2.0], [0.6, 2.0]]).unwrap()];
    let cfg = Config {
        max_iter: 1,
        ..Config::default()
    };
    let mut ctl = Ctl::new(cfg).unwrap();
    let inp = input(&wall);
    // A remembered plan that walks into the wall: the capture steps (at rest:
    // feet under the CoM, far from the wall) must win.
    ctl.memory.has_plan = true;
    ctl.memory.stance = inp.stance_side;
    ctl.memory.plan = SVector::<f64, 6>::from([0.15, 0.0, 0.3, 0.0, 0.45, 0.0]);
    let out = ctl.step(&inp, None);
    assert_eq!(out.status, CycleStatus::BudgetExhausted);
    assert_eq!(out.info.source, CommandSource::CaptureStep);
    let v = relax::class_violation(
        &ctl.last_assembly().qp,
        &ctl.last_assembly().rows,
        &ctl.variables_of(&out.plan),
    );
    assert!(v.safety <= 1e-9 && v.reach <= 1e-9, "{v:?}");
    // A remembered plan that satisfies every row is used as it is.
    let asm = ctl.last_assembly().clone();
    let good = ctl.solver().with_max_iter(100).solve(&asm.qp, &[false; 48]);
    assert!(good.status.is_solved());
    let good_feet = ctl.feet_of(&asm.prediction, &good.x);
    ctl.memory.has_plan = true;
    ctl.memory.stance = inp.stance_side;
    for (k, f) in good_feet.iter().enumerate() {
        ctl.memory.plan[2 * k] = f.x;
        ctl.memory.plan[2 * k + 1] = f.y;
    }
    let out = ctl.step(&inp, None);
    assert_eq!(out.info.source, CommandSource::PreviousPlan);
    assert_eq!(out.plan.feet, good_feet);
    assert!((ctl.variables_of(&out.plan) - good.x).amax() < 1e-12);
}

#[test]
fn long_horizons_are_accepted_and_their_plans_are_lip_rollouts() {
    fn check<const N: usize, const NV: usize, const NC: usize>() {
        let mut ctl = Controller::<N, NV, NC, 8>::new(Config::default()).unwrap();
        let wall = [Poly::new(&[[1.5, -2.0], [2.5, -2.0], [2.5, 0.3], [1.5, 0.3]]).unwrap()];
        let mut inp = input(&wall);
        inp.com_velocity = Vector2::new(0.4, 0.1);
        let out = ctl.step(&inp, None);
        assert_eq!(out.status, CycleStatus::Optimal, "N = {N}");
        assert!(out.info.max_violation <= 1e-9);
        // The returned feet, rolled forward through the LIP, give the
        // returned states (the plan is the spec's, in world frame).
        let lip = *ctl.lip();
        let (mut p, mut v) = (out.plan.x0.position, out.plan.x0.velocity);
        for k in 0..N {
            (p, v) = lip.propagate(&p, &v, &out.plan.feet[k], 0.4);
            let s = out.plan.states[k];
            assert!((s.position - p).amax() <= 1e-12, "N = {N}, p_{}", k + 1);
            assert!((s.velocity - v).amax() <= 1e-12, "N = {N}, v_{}", k + 1);
            // Restart from the plan's own state so the check stays local
            // (a forward rollout over many steps amplifies rounding by
            // cosh(beta T)^k).
            (p, v) = (s.position, s.velocity);
        }
        assert_eq!(out.foot_target, out.plan.feet[0]);
    }
    check::<10, 20, { constraint_capacity(10, 8, false) }>();
    check::<20, 40, { constraint_capacity(20, 8, false) }>();
}

#[test]
fn non_finite_input_holds() {
    let mut ctl = Ctl::new(Config::default()).unwrap();
    let mut inp = input(&[]);
    inp.com_velocity.x = f64::NAN;
    let out = ctl.step(&inp, None);
    assert_eq!(out.status, CycleStatus::InvalidInput(InputError::State));
    assert_eq!(out.foot_target, inp.stance_foot);
    assert_eq!(out.info.source, CommandSource::Hold);
    inp.com_velocity.x = 0.0;
    inp.goal.y = f64::INFINITY;
    assert_eq!(
        ctl.step(&inp, None).status,
        CycleStatus::InvalidInput(InputError::Goal)
    );
}

#[test]
fn fuzz_regression_huge_coordinates_are_invalid_input() {
    // Found by `cargo fuzz run step`: a CoM at x = 1.2e111 m gave a plan whose
    // reachability rows failed by 1e80 (all precision lost). Such inputs are
    // now rejected as out of range.
    let mut ctl = Ctl::new(Config::default()).unwrap();
    let mut inp = input(&[]);
    inp.com_position = Vector2::new(1.210_696_639_093_781_8e111, -1.2e-59);
    inp.stance_foot = Vector2::new(1.2e111, 0.0);
    inp.time_in_step = -1.2e-59;
    let out = ctl.step(&inp, None);
    assert_eq!(out.status, CycleStatus::InvalidInput(InputError::State));
    assert!(output_is_finite(&out));
}

#[test]
fn budget_exhaustion_falls_back_to_finite_command() {
    let cfg = Config {
        max_iter: 1,
        ..Config::default()
    };
    let mut ctl = Ctl::new(cfg).unwrap();
    let out = ctl.step(&input(&[]), None);
    assert_eq!(out.status, CycleStatus::BudgetExhausted);
    assert_eq!(out.info.source, CommandSource::CaptureStep);
    assert!(output_is_finite(&out));
    assert_eq!(out.turning_rate, 0.0);
}

/// `CycleInput::speed_cap` bounds the planned longitudinal velocity at every
/// step end; a cap at or above `vx_max` is no cap, bit for bit; a negative or
/// NaN cap is a cap of 0.
#[test]
fn the_speed_cap_bounds_the_planned_longitudinal_velocity() {
    let moving = |cap: f64| CycleInput {
        com_velocity: Vector2::new(0.1, 0.0),
        speed_cap: cap,
        ..input(&[])
    };
    let lon =
        |s: &LipState| s.velocity.x * libm::cos(s.heading) + s.velocity.y * libm::sin(s.heading);
    let free = Ctl::new(Config::default())
        .unwrap()
        .step(&moving(NO_SPEED_CAP), None);
    assert_eq!(free.status, CycleStatus::Optimal);
    // Without a cap the plan speeds up towards the goal, past the cap below.
    assert!(free.plan.states.iter().any(|s| lon(s) > 0.25));
    for cap in [0.2, 0.15] {
        let out = Ctl::new(Config::default())
            .unwrap()
            .step(&moving(cap), None);
        assert_eq!(out.status, CycleStatus::Optimal, "cap {cap}");
        for s in &out.plan.states {
            assert!(lon(s) <= cap + 1e-9, "cap {cap}: {}", lon(s));
        }
    }
    let vx_max = Config::default().vx_max;
    for cap in [vx_max, 2.0 * vx_max] {
        let out = Ctl::new(Config::default())
            .unwrap()
            .step(&moving(cap), None);
        assert_eq!(out, free, "cap {cap}");
    }
    let zero = Ctl::new(Config::default())
        .unwrap()
        .step(&moving(0.0), None);
    for cap in [-1.0, f64::NAN, f64::NEG_INFINITY] {
        let out = Ctl::new(Config::default())
            .unwrap()
            .step(&moving(cap), None);
        assert_eq!(out, zero, "cap {cap}");
    }
}
