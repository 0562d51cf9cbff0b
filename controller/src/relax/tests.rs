extern crate std;

use super::*;
use crate::constraints::RowKind;
use crate::qp::{QpSolution, QpStatus};
use crate::{Assembly, Config, ConvexPolygon, CycleInput, PaperController, Side};
use nalgebra::Vector2;

/// The scheme's limits in these tests: 64 iterations a solve, 2,048 a cycle,
/// 12 probes a search, no give-way.
fn params<'a, const NC: usize>(
    gait_cap: f64,
    capture: Option<CaptureBounds>,
    certificate: Option<&'a nalgebra::SVector<f64, NC>>,
) -> Params<'a, NC> {
    Params {
        max_iter: 64,
        budget: 2048,
        probes: 12,
        gait_cap,
        capture,
        certificate,
        give_way: None,
        moving: None,
    }
}

const NC: usize = crate::constraint_capacity(3, 8, false);
/// Random cycles (about 4 in 5 are infeasible).
const CASES: usize = 1000;

/// Counts the solves of the priority scheme.
struct Counting(usize);
impl QpBackend<6, NC> for Counting {
    fn solve_qp(
        &mut self,
        solver: &DualActiveSet<6, NC>,
        qp: &DenseQp<6, NC>,
        prefer: &[bool; NC],
    ) -> crate::qp::QpSolution<6, NC> {
        self.0 += 1;
        solver.solve(qp, prefer)
    }

    fn solve_reprobe(
        &mut self,
        solver: &DualActiveSet<6, NC>,
        qp: &DenseQp<6, NC>,
        h: &SVector<f64, NC>,
        enabled: &[bool; NC],
        prefer: &[bool; NC],
        budget: u32,
        state: &mut Reprobe<6, NC>,
    ) -> crate::qp::QpSolution<6, NC> {
        self.0 += 1;
        solver.solve_reprobe(qp, h, enabled, prefer, budget, state)
    }
}

/// Deterministic uniform numbers in [0, 1) (64-bit LCG, top bits).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }

    /// One to three axis-aligned boxes (m, world), the rest of the array a
    /// placeholder triangle, and how many: centres from 0.3 m to `ahead`
    /// along `dir` and within `aside` along `side`, half-sizes from 0.1 m to
    /// `half`.
    fn boxes_ahead(
        &mut self,
        dir: Vector2<f64>,
        side: Vector2<f64>,
        ahead: f64,
        aside: f64,
        half: f64,
    ) -> ([ConvexPolygon<8>; 3], usize) {
        let mut obstacles =
            [ConvexPolygon::<8>::new(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap(); 3];
        let n_obs = 1 + (self.next() * 3.0) as usize;
        for o in obstacles.iter_mut().take(n_obs) {
            let c = dir * self.range(0.3, ahead) + side * self.range(-aside, aside);
            let (a, b) = (self.range(0.1, half), self.range(0.1, half));
            *o = ConvexPolygon::hull(&[
                [c.x - a, c.y - b],
                [c.x + a, c.y - b],
                [c.x + a, c.y + b],
                [c.x - a, c.y + b],
            ])
            .unwrap();
        }
        (obstacles, n_obs)
    }
}

/// The nominal QP with the gait and safety rows relaxed by `gait` and
/// `safety` (`None`: left out) is empty, as proven by a Farkas
/// certificate checked here independently of the solver (`y >= 0`,
/// `G'y = 0` to 1e-9, `h'y < 0`). `confined`: only these safety rows take
/// the safety relaxation, the others keep their nominal right-hand side.
fn certified_empty(
    solver: &DualActiveSet<6, NC>,
    asm: &Assembly<3, 6, NC, 8>,
    gait: Option<f64>,
    safety: Option<f64>,
    capture: Option<(CaptureBounds, f64)>,
    confined: Option<&[bool; NC]>,
) -> bool {
    let keep = Keep {
        safety,
        gait,
        capture: capture.map(|c| c.1),
    };
    let bounds = capture.map(|c| c.0);
    let mut qp = DenseQp::<6, NC>::with_q(asm.qp.q);
    for (i, ((g, h), id)) in asm.qp.rows().zip(&asm.rows).enumerate() {
        if let Some((rhs, _)) = keep.rhs(id.kind, h, bounds.as_ref()) {
            let out = confined.is_some_and(|c| !c[i]) && RowClass::of(id.kind) == RowClass::Safety;
            qp.push_row(&g, if out { h } else { rhs }).unwrap();
        }
    }
    let sol = solver.with_max_iter(500).solve(&qp, &[false; NC]);
    if sol.status != QpStatus::Infeasible {
        return false;
    }
    let y = &sol.lambda;
    let mut gty = SVector::<f64, 6>::zeros();
    let mut hty = 0.0;
    for (i, (g, h)) in qp.rows().enumerate() {
        assert!(y[i] >= 0.0);
        gty += g * y[i];
        hty += h * y[i];
    }
    gty.amax() <= 1e-9 * (1.0 + y.amax()) && hty < 0.0
}

/// On random cycles of a robot walking into nearby boxes, every infeasible
/// nominal QP gets a relaxed plan that keeps reachability and each class
/// within its reported relaxation, and each reported relaxation is
/// minimal in the priority order: 1e-6 (relative, plus 1e-6 absolute) less
/// is certified infeasible, a safety relaxation comes only when the gait
/// rows at the cap cannot make the problem feasible, and (half of the
/// cases run with the capturability bound on) the bound is relaxed only
/// when reachability alone cannot meet it.
#[test]
fn relaxations_are_minimal_in_priority_order() {
    let mut rng = Lcg(0x005e_ed0f_5afe);
    let mut ctl = PaperController::new(Config::default()).unwrap();
    let cap = ctl.config().max_gait_relaxation;
    let mut asm = Assembly::default();
    let (mut infeasible, mut stage1, mut stage2, mut stage3, mut stage4) = (0, 0, 0, 0, 0);
    // Cycles whose safety relaxation was confined to some of the safety rows.
    let mut confined = 0usize;
    let less = |e: f64| e - 1e-6 * (1.0 + e);
    let mut solves = [0usize; 32];
    let kappa =
        crate::constraints::Condensed::<3>::new(&crate::lip::Lip::new(9.81, 1.0, 0.4)).kappa;
    for case in 0..CASES {
        let delta = if rng.next() < 0.5 { 0.0 } else { 0.2 };
        let capture_fraction = if case % 2 == 0 { Some(0.92) } else { None };
        ctl = PaperController::new(Config {
            delta,
            capture_fraction,
            ..Config::default()
        })
        .unwrap();
        let th = rng.range(-3.0, 3.0);
        let dir = Vector2::new(libm::cos(th), libm::sin(th));
        let side = Vector2::new(-dir.y, dir.x);
        let speed = rng.range(0.2, 1.2);
        let v = dir * speed + side * rng.range(-0.3, 0.3);
        let (obstacles, n_obs) = rng.boxes_ahead(dir, side, 1.6, 0.8, 0.8);
        let input = CycleInput {
            com_position: Vector2::zeros(),
            com_velocity: v,
            heading: th + rng.range(-0.3, 0.3),
            turning_rate: rng.range(-0.3, 0.3),
            stance_foot: dir * rng.range(-0.2, 0.2) + side * rng.range(-0.15, 0.15),
            stance_side: if rng.next() < 0.5 {
                Side::Left
            } else {
                Side::Right
            },
            time_in_step: rng.range(0.0, 0.4),
            goal: dir * 10.0,
            obstacles: &obstacles[..n_obs],
            obstacle_velocities: &[],
            obstacle_velocity_radii: &[],
            speed_cap: crate::NO_SPEED_CAP,
        };
        ctl.assemble(&input, None, &mut asm).unwrap();
        let solver = ctl.solver();
        // The nominal solve leaves its factor in `state` (as the
        // controller's does) for the probes of the cases that hand it over.
        let mut state = Reprobe::new(&asm.qp);
        let nominal = solver.with_max_iter(64).solve_reprobe(
            &asm.qp,
            &asm.qp.h,
            &[true; NC],
            &[false; NC],
            64,
            &mut state,
        );
        if !nominal.status.is_infeasible() {
            continue;
        }
        infeasible += 1;
        // The nominal solve's certificate is one of the nominal QP
        // (`y >= 0` on the used rows, 0 beyond, `G'y = 0`, `h'y < 0`), so
        // of every relaxation the scheme bounds with it. Every other case
        // hands it over (as the controller does), the rest run without.
        let y = &nominal.lambda;
        let m = asm.qp.m;
        assert!(y.iter().take(m).all(|&v| v >= 0.0), "case {case}");
        assert!(y.iter().skip(m).all(|&v| v == 0.0), "case {case}");
        let scale: f64 = (0..m).map(|i| y[i] * asm.qp.row(i).norm()).sum();
        let gty = (0..m).fold(nalgebra::SVector::<f64, 6>::zeros(), |acc, i| {
            acc + asm.qp.row(i) * y[i]
        });
        assert!(gty.amax() <= 1e-9 * scale, "case {case}: G'y = {gty:?}");
        let yh: f64 = (0..m).map(|i| y[i] * asm.qp.h[i]).sum();
        assert!(yh < 0.0, "case {case}: y'h = {yh}");
        let certificate = (case % 2 == 0).then_some(y);
        if case % 4 == 3 {
            // Some probes start from scratch.
            state = Reprobe::new(&asm.qp);
        }
        let cb = CaptureBounds::new(ctl.config(), kappa, asm.prediction.heading.omega_bar);
        assert_eq!(cb.is_some(), capture_fraction.is_some());
        let mut count = Counting(0);
        let r = relax(
            solver,
            &mut count,
            &asm.qp,
            &asm.rows,
            params(cap, cb, certificate),
            &mut state,
        )
        .unwrap_or_else(|e| panic!("case {case}: {e:?}"));
        solves[count.0.min(31)] += 1;
        let v = class_violation(&asm.qp, &asm.rows, &r.u);
        let (eg, es, ec) = (r.eps_gait, r.eps_safety, r.eps_capture);
        // The capturability bound, relaxed by `ec`, holds.
        let with_capture = |e: f64| cb.map(|c| (c, e));
        if let Some(c) = cb {
            for ((g, h), id) in asm.qp.rows().zip(&asm.rows) {
                if let Some(room) = c.of(id.kind) {
                    let e = g.dot(&r.u) - h - room;
                    assert!(e <= ec * (1.0 + 1e-9) + 1e-9, "case {case}: {e} {r:?}");
                }
            }
        } else {
            assert_eq!(ec, 0.0);
        }
        assert!(v.reach <= 1e-9, "case {case}: {v:?}");
        assert!(
            v.gait <= eg * (1.0 + 1e-9) + 1e-9,
            "case {case}: {v:?} {r:?}"
        );
        assert!(
            v.safety <= es * (1.0 + 1e-9) + 1e-9,
            "case {case}: {v:?} {r:?}"
        );
        // The safety rows outside the conflict keep their full margin.
        for (((g, h), id), &c) in asm.qp.rows().zip(&asm.rows).zip(&r.conflict) {
            if RowClass::of(id.kind) == RowClass::Safety && !c {
                assert!(g.dot(&r.u) - h <= 1e-9, "case {case}: {id:?} {r:?}");
            } else {
                assert!(!c || es > 0.0, "case {case}: {r:?}");
            }
        }
        let n_conflict = r.conflict.iter().filter(|&&c| c).count();
        confined += usize::from(n_conflict > 0 && n_conflict < safety_count(&asm));
        if ec > 0.0 {
            // Stage 4: the least relaxation of the capturability bound
            // with reachability alone, then the least safety and gait
            // relaxations under it.
            assert!(
                certified_empty(solver, &asm, None, None, with_capture(less(ec)), None),
                "case {case}: {r:?}: capture not minimal"
            );
            if es > 1e-6 {
                assert!(
                    certified_empty(solver, &asm, None, Some(less(es)), with_capture(ec), None),
                    "case {case}: {r:?}: safety not minimal"
                );
            }
            if eg > 1e-6 {
                assert!(
                    certified_empty(
                        solver,
                        &asm,
                        Some(less(eg)),
                        Some(es),
                        with_capture(ec),
                        Some(&r.conflict)
                    ),
                    "case {case}: {r:?}: gait not minimal"
                );
            }
            stage4 += 1;
            continue;
        }
        if es == 0.0 {
            // Stage 1 (or stage 3 without a safety relaxation): the least
            // gait relaxation with safety kept.
            assert_eq!(r.level, RelaxLevel::Gait);
            assert!(eg > 0.0, "case {case}: the nominal QP is infeasible");
            assert!(
                certified_empty(
                    solver,
                    &asm,
                    Some(less(eg)),
                    Some(0.0),
                    with_capture(0.0),
                    None
                ),
                "case {case}: {r:?} not minimal"
            );
            stage1 += 1;
            continue;
        }
        assert_eq!(r.level, RelaxLevel::Safety);
        // Safety gives way only when the capped gait rows cannot help.
        assert!(
            certified_empty(solver, &asm, Some(cap), Some(0.0), with_capture(0.0), None),
            "case {case}"
        );
        // The least safety relaxation with the gait rows at the cap
        // (stage 2) or left out (stage 3; under the capturability bound
        // when on).
        let gait_bound = (eg <= cap * (1.0 + 1e-9)).then_some(cap);
        assert!(
            certified_empty(
                solver,
                &asm,
                gait_bound,
                Some(less(es)),
                with_capture(0.0),
                None
            ),
            "case {case}: {r:?}: safety not minimal"
        );
        // Then the least gait relaxation under that safety relaxation.
        if eg > 1e-6 {
            assert!(
                certified_empty(
                    solver,
                    &asm,
                    Some(less(eg)),
                    Some(es),
                    with_capture(0.0),
                    Some(&r.conflict)
                ),
                "case {case}: {r:?}: gait not minimal"
            );
        }
        if gait_bound.is_some() {
            stage2 += 1;
        } else {
            stage3 += 1;
        }
    }
    std::println!(
        "{infeasible} infeasible: {stage1} stage 1, {stage2} stage 2, {stage3} stage 3, \
         {stage4} stage 4; {confined} with the safety relaxation confined to the conflict; \
         solves of the priority scheme (count: cycles): {:?}",
        solves
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .collect::<std::vec::Vec<_>>()
    );
    assert!(
        stage1 >= 20 && stage2 >= 50 && stage3 >= 20 && stage4 >= 10,
        "{stage1} {stage2} {stage3} {stage4}"
    );
}

/// The number of safety rows of a cycle's QP.
/// The paper controller's QP for `input`, its nominal solve (asserted
/// infeasible: the case must need the priority scheme) and the cycle's
/// capturability bounds.
fn infeasible_cycle(
    ctl: &PaperController,
    input: &CycleInput<'_, 8>,
) -> (
    Assembly<3, 6, NC, 8>,
    QpSolution<6, NC>,
    Option<CaptureBounds>,
) {
    let mut asm = Assembly::default();
    ctl.assemble(input, None, &mut asm).unwrap();
    let nominal = ctl.solver().with_max_iter(64).solve(&asm.qp, &[false; NC]);
    assert!(nominal.status.is_infeasible(), "{:?}", nominal.status);
    let cb = CaptureBounds::new(ctl.config(), ctl_kappa(), asm.prediction.heading.omega_bar);
    (asm, nominal, cb)
}

/// The worst violation of the safety rows of obstacle `j` (its LDCBF and
/// foot-clearance rows) by the plan `u`, m.
fn worst_violation(asm: &Assembly<3, 6, NC, 8>, j: u32, u: &SVector<f64, 6>) -> f64 {
    asm.qp
        .rows()
        .zip(&asm.rows)
        .filter(
            |(_, id)| matches!(id.kind, RowKind::Ldcbf(i) | RowKind::FootClearance(i) if i == j),
        )
        .map(|((g, h), _)| g.dot(u) - h)
        .fold(f64::NEG_INFINITY, f64::max)
}

fn safety_count(asm: &Assembly<3, 6, NC, 8>) -> usize {
    asm.rows
        .iter()
        .take(asm.qp.m)
        .filter(|id| RowClass::of(id.kind) == RowClass::Safety)
        .count()
}

/// The largest body-frame velocity component of a plan's `v_1 .. v_N`
/// (each in its step's heading frame), m/s.
fn fastest_component(out: &crate::CycleOutput<3>) -> f64 {
    out.plan
        .states
        .iter()
        .map(|s| {
            let (c, sn) = (libm::cos(s.heading), libm::sin(s.heading));
            let lon = c * s.velocity.x + sn * s.velocity.y;
            let lat = -sn * s.velocity.x + c * s.velocity.y;
            lon.abs().max(lat.abs())
        })
        .fold(0.0, f64::max)
}

/// A robot at the end of a step, walking at `vx_max` along x, pushed
/// sideways to `lateral` m/s, no obstacles, goal far ahead.
fn pushed(capture_fraction: Option<f64>, forward: f64, lateral: f64) -> crate::CycleOutput<3> {
    let mut ctl = PaperController::new(Config {
        capture_fraction,
        ..Config::default()
    })
    .unwrap();
    let input = CycleInput::<8> {
        com_position: Vector2::zeros(),
        com_velocity: Vector2::new(forward, lateral),
        heading: 0.0,
        turning_rate: 0.0,
        stance_foot: Vector2::new(-0.1, -0.1),
        stance_side: Side::Right,
        time_in_step: 0.4,
        goal: Vector2::new(20.0, 0.0),
        obstacles: &[],
        obstacle_velocities: &[],
        obstacle_velocity_radii: &[],
        speed_cap: crate::NO_SPEED_CAP,
    };
    ctl.step(&input, None)
}

/// Pushed to 0.75 m/s sideways (beyond `vy_max` = 0.4 m/s, but below the
/// capturable 0.92 |kappa| l_max = 0.898 m/s): the gait rows give way
/// beyond their cap (stage 3). Without the capturability bound the uniform
/// relaxation also lets the forward velocity exceed what any step within
/// reach can stop; with it every planned component stays capturable and
/// the bound itself is not relaxed.
#[test]
fn capturable_push_keeps_the_plan_capturable() {
    let kappa =
        crate::constraints::Condensed::<3>::new(&crate::lip::Lip::new(9.81, 1.0, 0.4)).kappa;
    let limit = kappa.abs() * Config::default().l_max;
    let speed = 0.92 * limit;
    let on = pushed(Some(0.92), 0.8, 0.75);
    let off = pushed(None, 0.8, 0.75);
    std::println!(
        "on: {:?} fastest {:.3}; off: {:?} fastest {:.3}; limit {limit:.3}",
        on.info,
        fastest_component(&on),
        off.info,
        fastest_component(&off)
    );
    assert!(on.info.relax_gait > 0.1, "{:?}", on.info);
    assert_eq!(on.info.relax_capture, 0.0);
    assert!(fastest_component(&on) <= speed + 1e-9);
    assert!(fastest_component(&off) > limit, "{:?}", off.plan);
}

/// Pushed forward beyond the bound. At 0.95 m/s (above the bound's
/// 0.898 m/s, below `|kappa| l_max` = 0.976 m/s) no step within reach
/// meets the bound at once (`v_1 >= cosh(beta T) v_0 - beta sinh(beta T)
/// l_max` = 0.927 m/s): the bound is relaxed (stage 4, reported in
/// `relax_capture`) by just that excess, no planned velocity exceeds the
/// relaxed bound, and from the planned `v_1` the bound holds again. At
/// 1.1 m/s the LIP cannot be stopped: the relaxation is reported,
/// large, and the plan (the slowest possible) still speeds up.
#[test]
fn push_beyond_the_bound_is_detected() {
    let lip = crate::lip::Lip::new(9.81, 1.0, 0.4);
    let l_max = Config::default().l_max;
    let kappa = crate::constraints::Condensed::<3>::new(&lip).kappa;
    let speed = 0.92 * kappa.abs() * l_max;
    let bs = lip.beta * lip.sinh_bt;
    // The slowest reachable velocities from v_0.
    let slowest = |v0: f64| {
        let v1 = lip.cosh_bt * v0 - bs * l_max;
        [v1, lip.cosh_bt * v1 - bs * l_max]
    };
    let out = pushed(Some(0.92), 0.95, 0.0);
    let v: std::vec::Vec<f64> = out.plan.states.iter().map(|s| s.velocity.x).collect();
    std::println!("0.95 m/s: {:?} {v:?}", out.info);
    assert!(
        (out.info.relax_capture - (slowest(0.95)[0] - speed)).abs() < 1e-6,
        "{:?}",
        out.info
    );
    let relaxed = speed + out.info.relax_capture + 1e-9;
    assert!(v[0] < 0.95 && v.iter().all(|&x| x <= relaxed), "{v:?}");
    let next = pushed(Some(0.92), v[0], 0.0);
    assert_eq!(next.info.relax_capture, 0.0, "{:?}", next.info);
    let out = pushed(Some(0.92), 1.1, 0.0);
    let v: std::vec::Vec<f64> = out.plan.states.iter().map(|s| s.velocity.x).collect();
    std::println!("1.1 m/s: {:?} {v:?}", out.info);
    assert!(out.info.relax_capture > slowest(1.1)[1] - speed - 1e-6);
    assert!(v[0] > 1.1 && v[1] > v[0], "{v:?}");
    // Not reported when the robot is within the bound.
    let within = pushed(Some(0.92), 0.85, 0.0);
    assert_eq!(within.info.relax_capture, 0.0, "{:?}", within.info);
}

/// The corridor case: walking fast along a corridor (goal ahead and to the
/// left) into a wall fragment too close to stop in front of, with the left
/// side wall beside. The nominal QP is infeasible and only the safety rows
/// can give way; the relaxed plan keeps every row of the side wall at its
/// nominal right-hand side (full margin) and relaxes only the fragment's,
/// by the least uniform amount. The uniform relaxation (every safety row
/// by the same amount), solved here directly, does use the side wall's
/// margin: without the confinement this test fails.
#[test]
fn a_conflict_ahead_leaves_the_side_wall_its_margin() {
    let ctl = PaperController::new(Config::default()).unwrap();
    let cap = ctl.config().max_gait_relaxation;
    let side =
        ConvexPolygon::<8>::new(&[[-1.0, 0.45], [3.0, 0.45], [3.0, 0.6], [-1.0, 0.6]]).unwrap();
    let fragment =
        ConvexPolygon::<8>::new(&[[0.45, -0.6], [0.6, -0.6], [0.6, 0.2], [0.45, 0.2]]).unwrap();
    let obstacles = [side, fragment];
    let input = CycleInput {
        com_position: Vector2::zeros(),
        com_velocity: Vector2::new(0.8, 0.0),
        heading: 0.0,
        turning_rate: 0.0,
        stance_foot: Vector2::new(0.0, -0.1),
        stance_side: Side::Right,
        time_in_step: 0.4,
        goal: Vector2::new(10.0, 10.0),
        obstacles: &obstacles,
        obstacle_velocities: &[],
        obstacle_velocity_radii: &[],
        speed_cap: crate::NO_SPEED_CAP,
    };
    let solver = ctl.solver();
    let (asm, nominal, cb) = infeasible_cycle(&ctl, &input);
    let mut count = Counting(0);
    let r = relax(
        solver,
        &mut count,
        &asm.qp,
        &asm.rows,
        params(cap, cb, Some(&nominal.lambda)),
        &mut Reprobe::new(&asm.qp),
    )
    .unwrap();
    assert_eq!(r.level, RelaxLevel::Safety, "{r:?}");
    assert!(r.eps_safety > 1e-3, "{r:?}");
    let worst = |j: u32, u: &SVector<f64, 6>| worst_violation(&asm, j, u);
    std::println!(
        "{r:?}, {} solves; side wall {:.4}, fragment {:.4}",
        count.0,
        worst(0, &r.u),
        worst(1, &r.u)
    );
    assert!(worst(0, &r.u) <= 1e-9, "the side wall gave way: {r:?}");
    assert!(worst(1, &r.u) > 1e-3 && worst(1, &r.u) <= r.eps_safety * (1.0 + 1e-9) + 1e-9);
    let n_side = asm
        .rows
        .iter()
        .take(asm.qp.m)
        .filter(|id| matches!(id.kind, RowKind::Ldcbf(0) | RowKind::FootClearance(0)))
        .count();
    let n_safety = asm
        .rows
        .iter()
        .take(asm.qp.m)
        .filter(|id| RowClass::of(id.kind) == RowClass::Safety)
        .count();
    let relaxed = r.conflict.iter().filter(|&&c| c).count();
    assert!(relaxed >= 1 && relaxed <= n_safety - n_side, "{r:?}");
    for (id, &c) in asm.rows.iter().zip(&r.conflict).take(asm.qp.m) {
        assert!(!c || RowClass::of(id.kind) == RowClass::Safety);
    }
    // The uniform relaxation, for contrast: gait at the cap, every safety
    // row at `h + eps_safety` (capturability at its ceiling).
    let keep = Keep {
        safety: Some(r.eps_safety),
        gait: Some(r.eps_gait),
        capture: cb.map(|_| 0.0),
    };
    let mut qp = DenseQp::<6, NC>::with_q(asm.qp.q);
    for ((g, h), id) in asm.qp.rows().zip(&asm.rows) {
        if let Some((rhs, _)) = keep.rhs(id.kind, h, cb.as_ref()) {
            qp.push_row(&g, rhs).unwrap();
        }
    }
    let uniform = solver.with_max_iter(500).solve(&qp, &[false; NC]);
    assert_eq!(uniform.status, QpStatus::Solved);
    std::println!("uniform: side wall {:.4}", worst(0, &uniform.x));
    assert!(
        worst(0, &uniform.x) > 1e-3,
        "the case does not test anything"
    );
}

/// `kappa` of Table I's step map, 1/s.
fn ctl_kappa() -> f64 {
    crate::constraints::Condensed::<3>::new(&crate::lip::Lip::new(9.81, 1.0, 0.4)).kappa
}

/// On a cycle that gives way (`Params::give_way`), where the first probe
/// starts from scratch with the warm-start rows marked: the marks choose the
/// path only, never the answer. On random infeasible cycles (a robot walking
/// into one to three boxes, as in `relaxations_are_minimal_in_priority_order`),
/// the scheme run with the rows of the nominal solve's active set marked and
/// run with none marked reports the same stage and relaxations (to their
/// tolerance, 1e-9 relative and absolute per probe) and, when the same rows
/// took the safety relaxation, the same plan (the optimum of the same strictly
/// convex QP). (The solves are printed, not asserted: which start is
/// cheaper depends on the marks; the controller's, the rows of the last
/// cycle's relaxed plan, are measured on the firmware's walk-into pass.)
#[test]
fn give_way_marks_change_the_path_not_the_answer() {
    let mut rng = Lcg(0x9177_e5a1);
    let ctl = PaperController::new(Config::default()).unwrap();
    let solver = ctl.solver();
    let mut asm = Assembly::default();
    let (mut cases, mut same_rows) = (0usize, 0usize);
    let (mut solves_marked, mut solves_plain) = (0usize, 0usize);
    for _ in 0..300 {
        let th = rng.range(-3.0, 3.0);
        let dir = Vector2::new(libm::cos(th), libm::sin(th));
        let side = Vector2::new(-dir.y, dir.x);
        let (obstacles, n_obs) = rng.boxes_ahead(dir, side, 1.2, 0.6, 0.6);
        let input = CycleInput {
            com_position: Vector2::zeros(),
            com_velocity: dir * rng.range(0.2, 0.9),
            heading: th,
            turning_rate: 0.0,
            stance_foot: side * rng.range(-0.15, 0.15),
            stance_side: Side::Left,
            time_in_step: rng.range(0.0, 0.4),
            // Away from the boxes, as the give-way goal is.
            goal: -dir,
            obstacles: &obstacles[..n_obs],
            obstacle_velocities: &[],
            obstacle_velocity_radii: &[],
            speed_cap: crate::NO_SPEED_CAP,
        };
        ctl.assemble(&input, None, &mut asm).unwrap();
        let mut state = Reprobe::new(&asm.qp);
        let nominal = solver.solve_reprobe(
            &asm.qp,
            &asm.qp.h,
            &[true; NC],
            &[false; NC],
            64,
            &mut state,
        );
        if !nominal.status.is_infeasible() {
            continue;
        }
        let mut marks = [false; NC];
        for &a in nominal.active_set() {
            marks[usize::from(a)] = true;
        }
        let run = |marks: &[bool; NC], count: &mut Counting| {
            let mut state = Reprobe::new(&asm.qp);
            let p = Params {
                give_way: Some(marks),
                ..params(0.1, None, Some(&nominal.lambda))
            };
            relax(solver, count, &asm.qp, &asm.rows, p, &mut state).unwrap()
        };
        let (mut c1, mut c2) = (Counting(0), Counting(0));
        let a = run(&marks, &mut c1);
        let b = run(&[false; NC], &mut c2);
        cases += 1;
        solves_marked += c1.0;
        solves_plain += c2.0;
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-6 * (1.0 + x.abs().max(y.abs()));
        assert_eq!(a.level, b.level, "{a:?} {b:?}");
        assert!(close(a.eps_safety, b.eps_safety), "{a:?} {b:?}");
        assert!(close(a.eps_gait, b.eps_gait), "{a:?} {b:?}");
        if a.conflict == b.conflict {
            same_rows += 1;
            assert!((a.u - b.u).amax() <= 1e-6, "{a:?} {b:?}");
        }
    }
    std::println!(
        "{cases} infeasible cycles, {same_rows} with the same rows relaxed; solves {solves_marked} marked, {solves_plain} not"
    );
    assert!(
        cases >= 100 && same_rows * 10 >= cases * 9,
        "{cases} {same_rows}"
    );
}

/// Moving rows first (module docs): a robot walking at 0.6 m/s between two
/// walls 0.9 m apart, a person (a 0.5 m square) 0.9 m ahead walking at it at
/// 0.6 m/s, goal behind and beside (as a give-way goal can be). The nominal QP is
/// infeasible with the person's rows in the conflict; with the person's rows
/// (`Params::moving`) given way first, every wall row keeps its nominal
/// right-hand side and only the person's rows take the relaxation. Every
/// safety row relaxed alike (no `moving`), a wall row gives way.
#[test]
fn a_person_gives_way_before_the_walls() {
    let ctl = PaperController::new(Config::default()).unwrap();
    let wall = |y0: f64, y1: f64| {
        ConvexPolygon::<8>::new(&[[-2.0, y0], [6.0, y0], [6.0, y1], [-2.0, y1]]).unwrap()
    };
    let person =
        ConvexPolygon::<8>::new(&[[0.65, -0.25], [1.15, -0.25], [1.15, 0.25], [0.65, 0.25]])
            .unwrap();
    let obstacles = [wall(0.45, 0.9), wall(-0.9, -0.45), person];
    let velocities = [Vector2::zeros(), Vector2::zeros(), Vector2::new(-0.6, 0.0)];
    let input = CycleInput {
        com_position: Vector2::new(0.0, -0.1),
        com_velocity: Vector2::new(0.6, 0.0),
        heading: 0.0,
        turning_rate: 0.0,
        stance_foot: Vector2::new(0.0, -0.2),
        stance_side: Side::Right,
        time_in_step: 0.4,
        goal: Vector2::new(-0.5, -1.5),
        obstacles: &obstacles,
        obstacle_velocities: &velocities,
        obstacle_velocity_radii: &[],
        speed_cap: crate::NO_SPEED_CAP,
    };
    let solver = ctl.solver();
    let (asm, nominal, cb) = infeasible_cycle(&ctl, &input);
    let mut moving = [false; NC];
    for (m, id) in moving.iter_mut().zip(&asm.rows).take(asm.qp.m) {
        *m = matches!(id.kind, RowKind::Ldcbf(2) | RowKind::FootClearance(2));
    }
    let worst = |j: u32, u: &SVector<f64, 6>| worst_violation(&asm, j, u);
    let run = |moving: Option<&[bool; NC]>| {
        let p = Params {
            give_way: Some(&[false; NC]),
            moving,
            ..params(0.1, cb, Some(&nominal.lambda))
        };
        let r = relax(
            solver,
            &mut Counting(0),
            &asm.qp,
            &asm.rows,
            p,
            &mut Reprobe::new(&asm.qp),
        )
        .unwrap();
        let walls = worst(0, &r.u).max(worst(1, &r.u));
        std::println!("{r:?}: walls {walls:.4}, person {:.4}", worst(2, &r.u));
        (r, walls)
    };
    let (first, walls) = run(Some(&moving));
    assert_eq!(first.level, RelaxLevel::Safety, "{first:?}");
    assert!(walls <= 1e-9, "a wall gave way: {first:?}");
    let person = worst(2, &first.u);
    assert!(person > 1e-3 && person <= first.eps_safety * (1.0 + 1e-9) + 1e-9);
    assert_eq!(first.conflict, moving);
    let (uniform, walls) = run(None);
    assert!(walls > 1e-3, "the case does not test anything: {uniform:?}");
}
