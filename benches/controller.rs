//! Criterion benchmarks of one controller cycle at the paper's configuration
//! (`PaperController`: N = 3, up to 8 active obstacles).
//!
//! The cycles are recorded from a closed loop run here: the robot walks from
//! (0, 0) to (10, 10) among the six obstacles of the SPEC's `paper` scenario,
//! with the controller called at 20 Hz (8 cycles per 0.4 s step) and the LIP
//! integrated in closed form. Benchmarks:
//!
//! * `step/warm`: `Controller::step` over the recorded sequence, in order, so the
//!   warm start works as on the robot;
//! * `step/cold`: the same cycles with the warm-start memory reset before each;
//! * `solve/cold`: the QP solve alone on the recorded QPs.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    Assembly, Config, ConvexPolygon, CycleInput, CycleStatus, PaperController, Side,
};

type Poly = ConvexPolygon<8>;

fn paper_obstacles() -> Vec<Poly> {
    let sets: [&[[f64; 2]]; 6] = [
        &[[2.0, 7.5], [1.5, 7.0], [1.8, 6.5]],
        &[[4.0, 6.5], [4.3, 6.8], [4.7, 6.5], [4.5, 6.2], [4.1, 6.2]],
        &[[7.0, 7.0], [7.5, 7.5], [8.0, 7.0], [7.5, 6.5]],
        &[[6.0, 2.5], [6.5, 2.0], [7.0, 2.5]],
        &[[1.5, 3.0], [1.8, 3.3], [2.2, 3.0], [2.0, 2.6], [1.6, 2.6]],
        &[[2.5, 3.5], [2.8, 3.8], [3.2, 3.5], [3.0, 3.1], [2.6, 3.1]],
    ];
    sets.iter()
        .map(|s| Poly::hull(s).expect("convex"))
        .collect()
}

/// A recorded cycle (owned copy of the input fields).
#[derive(Clone, Copy)]
struct Cycle {
    p: Vector2<f64>,
    v: Vector2<f64>,
    heading: f64,
    omega: f64,
    foot: Vector2<f64>,
    side: Side,
    t_in: f64,
}

fn input<'a>(c: &Cycle, goal: Vector2<f64>, obs: &'a [Poly]) -> CycleInput<'a, 8> {
    CycleInput {
        com_position: c.p,
        com_velocity: c.v,
        heading: c.heading,
        turning_rate: c.omega,
        stance_foot: c.foot,
        stance_side: c.side,
        time_in_step: c.t_in,
        goal,
        obstacles: obs,
    }
}

/// Runs the closed loop and records every cycle's input.
fn record(obs: &[Poly], goal: Vector2<f64>) -> Vec<Cycle> {
    let mut ctl = PaperController::new(Config::default()).expect("valid config");
    let lip = *ctl.lip();
    let mut c = Cycle {
        p: Vector2::zeros(),
        v: Vector2::zeros(),
        heading: 0.0,
        omega: 0.0,
        foot: Vector2::zeros(),
        side: Side::Left,
        t_in: 0.0,
    };
    let mut cycles = Vec::new();
    let dt = 0.05;
    for _ in 0..(8 * 150) {
        cycles.push(c);
        let out = ctl.step(&input(&c, goal, obs));
        assert!(out.status != CycleStatus::InvalidInput(ldcbf_controller::InputError::State));
        let target = out.foot_target;
        c.omega = out.turning_rate;
        let (p, v) = lip.propagate(&c.p, &c.v, &c.foot, dt);
        c.p = p;
        c.v = v;
        c.heading += c.omega * dt;
        c.t_in += dt;
        if c.t_in >= 0.4 - 1e-9 {
            c.t_in = 0.0;
            c.foot = target;
            c.side = c.side.opposite();
        }
        if (c.p - goal).norm() < 0.15 {
            break;
        }
    }
    cycles
}

fn bench(cr: &mut Criterion) {
    let obs = paper_obstacles();
    let goal = Vector2::new(10.0, 10.0);
    let cycles = record(&obs, goal);
    let mut group = cr.benchmark_group("paper_config");
    group.bench_function("step/warm", |b| {
        let mut ctl = PaperController::new(Config::default()).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            black_box(ctl.step(black_box(&input(c, goal, &obs))))
        })
    });
    group.bench_function("step/cold", |b| {
        let mut ctl = PaperController::new(Config::default()).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            ctl.reset();
            black_box(ctl.step(black_box(&input(c, goal, &obs))))
        })
    });
    let ctl = PaperController::new(Config::default()).unwrap();
    let qps: Vec<Assembly<3, 6, 48, 8>> = cycles
        .iter()
        .map(|c| {
            let mut a = Assembly::default();
            ctl.assemble(&input(c, goal, &obs), &mut a).unwrap();
            a
        })
        .collect();
    group.bench_function("solve/cold", |b| {
        let mut i = 0;
        b.iter(|| {
            let a = &qps[i % qps.len()];
            i += 1;
            black_box(ctl.solver().solve(black_box(&a.qp), &[false; 48], 64))
        })
    });
    group.finish();
    println!(
        "recorded {} cycles; final CoM distance to goal {:.3} m",
        cycles.len(),
        (cycles.last().unwrap().p - goal).norm()
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
