//! Criterion benchmarks of one controller cycle.
//!
//! Cycles are recorded from closed loops run here: the controller is called at
//! 20 Hz (8 cycles per 0.4 s step) and the LIP is integrated in closed form, the
//! swing foot landing at the last target at each step end (the simulator's loop
//! in miniature). Each benchmark replays the recorded inputs in order.
//!
//! * `paper_config/*`: `PaperController` (N = 3, capacity 8) walking from (0, 0)
//!   to (10, 10) among the six obstacles of the SPEC's `paper` scenario:
//!   `step/warm` (in order, warm start as on the robot), `step/cold` (memory reset
//!   before each cycle), `solve/cold` (the QP solve alone on the recorded QPs).
//! * `horizon/N`: the same walk with horizon N in {3, 5, 10} (capacity 8). N = 20
//!   is not benchmarked: in the condensed formulation the footstep weights grow
//!   like cosh(beta T)^N, the Hessian's condition number passes 1e13 at N = 10 and
//!   the Hessian is numerically indefinite from N = 14, so `Controller::new`
//!   rejects N = 20 (see the README's open points).
//! * `obstacles/K`: N = 3, obstacle capacity K in {0, 4, 8, 16, 32}, walking
//!   through a field of 0.2 m square posts on a 1 m grid (so that at least 32
//!   are within `r_active` = 4 m), warm-started.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    Assembly, Config, Controller, ConvexPolygon, CycleInput, InputError, Side, constraint_capacity,
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

/// Posts of 0.2 m on a 1 m grid over [-3, 13]^2, leaving a clear corridor of
/// half-width 0.5 m along the diagonal from (0, 0) to (10, 10).
fn post_field() -> Vec<Poly> {
    let mut out = Vec::new();
    for i in -3..=13 {
        for j in -3..=13 {
            let (x, y) = (i as f64 + 0.5, j as f64);
            if ((x - y) / 2f64.sqrt()).abs() < 0.8 {
                continue;
            }
            let sq = [
                [x - 0.1, y - 0.1],
                [x + 0.1, y - 0.1],
                [x + 0.1, y + 0.1],
                [x - 0.1, y + 0.1],
            ];
            out.push(Poly::new(&sq).expect("square"));
        }
    }
    out
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

/// Runs the closed loop with a controller of the given sizes and records every
/// cycle's input (at most 150 steps, until the CoM is within 0.15 m of the goal).
fn record<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    obs: &[Poly],
    goal: Vector2<f64>,
) -> Vec<Cycle> {
    let mut ctl = Controller::<N, NV, NC, NOBS>::new(Config::default()).expect("valid config");
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
        assert!(out.status != ldcbf_controller::CycleStatus::InvalidInput(InputError::State));
        let (p, v) = lip.propagate(&c.p, &c.v, &c.foot, dt);
        c.p = p;
        c.v = v;
        c.heading += c.omega * dt;
        c.t_in += dt;
        if c.t_in >= 0.4 - 1e-9 {
            c.t_in = 0.0;
            c.foot = out.foot_target;
            c.side = c.side.opposite();
            c.omega = out.turning_rate;
        }
        if (c.p - goal).norm() < 0.15 {
            break;
        }
    }
    cycles
}

/// Benchmarks `step` (warm) over cycles recorded with the same sizes.
fn bench_step<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    id: BenchmarkId,
    obs: &[Poly],
    goal: Vector2<f64>,
) {
    let cycles = record::<N, NV, NC, NOBS>(obs, goal);
    group.bench_function(id, |b| {
        let mut ctl = Controller::<N, NV, NC, NOBS>::new(Config::default()).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            black_box(ctl.step(black_box(&input(c, goal, obs))))
        })
    });
}

fn paper(cr: &mut Criterion) {
    const N: usize = 3;
    const NC: usize = constraint_capacity(3, 8, false);
    type Paper = Controller<3, 6, NC, 8>;
    let obs = paper_obstacles();
    let goal = Vector2::new(10.0, 10.0);
    let cycles = record::<N, 6, NC, 8>(&obs, goal);
    let mut group = cr.benchmark_group("paper_config");
    group.bench_function("step/warm", |b| {
        let mut ctl = Paper::new(Config::default()).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            black_box(ctl.step(black_box(&input(c, goal, &obs))))
        })
    });
    group.bench_function("step/cold", |b| {
        let mut ctl = Paper::new(Config::default()).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            ctl.reset();
            black_box(ctl.step(black_box(&input(c, goal, &obs))))
        })
    });
    let ctl = Paper::new(Config::default()).unwrap();
    let qps: Vec<Assembly<3, 6, NC, 8>> = cycles
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
            black_box(ctl.solver().solve(black_box(&a.qp), &[false; NC], 64))
        })
    });
    group.finish();
}

fn horizon(cr: &mut Criterion) {
    let obs = paper_obstacles();
    let goal = Vector2::new(10.0, 10.0);
    let mut group = cr.benchmark_group("horizon");
    bench_step::<3, 6, { constraint_capacity(3, 8, false) }, 8>(
        &mut group,
        BenchmarkId::from_parameter(3),
        &obs,
        goal,
    );
    bench_step::<5, 10, { constraint_capacity(5, 8, false) }, 8>(
        &mut group,
        BenchmarkId::from_parameter(5),
        &obs,
        goal,
    );
    bench_step::<10, 20, { constraint_capacity(10, 8, false) }, 8>(
        &mut group,
        BenchmarkId::from_parameter(10),
        &obs,
        goal,
    );
    group.finish();
}

fn obstacles(cr: &mut Criterion) {
    let obs = post_field();
    let goal = Vector2::new(10.0, 10.0);
    let mut group = cr.benchmark_group("obstacles");
    bench_step::<3, 6, { constraint_capacity(3, 0, false) }, 0>(
        &mut group,
        BenchmarkId::from_parameter(0),
        &obs,
        goal,
    );
    bench_step::<3, 6, { constraint_capacity(3, 4, false) }, 4>(
        &mut group,
        BenchmarkId::from_parameter(4),
        &obs,
        goal,
    );
    bench_step::<3, 6, { constraint_capacity(3, 8, false) }, 8>(
        &mut group,
        BenchmarkId::from_parameter(8),
        &obs,
        goal,
    );
    bench_step::<3, 6, { constraint_capacity(3, 16, false) }, 16>(
        &mut group,
        BenchmarkId::from_parameter(16),
        &obs,
        goal,
    );
    bench_step::<3, 6, { constraint_capacity(3, 32, false) }, 32>(
        &mut group,
        BenchmarkId::from_parameter(32),
        &obs,
        goal,
    );
    group.finish();
}

// Plots off: the workspace's plotters is built without system fonts (for the
// simulator's figures), which criterion's own plots would need.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = paper, horizon, obstacles
}
criterion_main!(benches);
