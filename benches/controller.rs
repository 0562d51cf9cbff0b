//! Criterion benchmarks of one controller cycle.
//!
//! Cycles are recorded from closed loops run here: the controller is called at
//! 20 Hz (8 cycles per 0.4 s step) and the LIP is integrated in closed form, the
//! swing foot landing at the last target at each step end (the simulator's loop
//! in miniature). Each benchmark replays the recorded inputs in order.
//!
//! * `paper_config/*`: `PaperController` (N = 3, capacity 8) walking from (0, 0)
//!   to (10, 10) among the six obstacles of the `paper` scenario:
//!   `step/warm` (in order, warm start as on the robot), `step/cold` (memory reset
//!   before each cycle), `solve/cold` (the QP solve alone on the recorded QPs),
//!   `step/warm-moving` (the same cycles with the six obstacles moving at the
//!   velocities of the firmware's second pass, `firmware/src/moving.rs`).
//! * `horizon/N`: the same walk with horizon N in {3, 5, 10, 20} (capacity 8,
//!   iteration budgets scaled by `Config::with_budgets_for_horizon`, i.e.
//!   unchanged at N = 3). The QP is solved in the predicted positions (Hessian
//!   `2 I` at every N, see `controller/src/constraints.rs`), so N = 20 works.
//! * `obstacles/K`: N = 3, obstacle capacity K in {0, 4, 8, 16, 32}, walking
//!   through a field of 0.2 m square posts on a 1 m grid (so that at least 32
//!   are within `r_active` = 4 m), warm-started.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{Assembly, Config, Controller, ConvexPolygon, constraint_capacity};
use ldcbf_nav::fixtures::{PAPER_GOAL, RecordedInput, paper_obstacles, walk};

type Poly = ConvexPolygon<8>;

// `WALK_INTO` (the firmware's third pass) is not benchmarked.
#[allow(dead_code)]
mod moving {
    include!("../firmware/src/moving.rs");
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

/// The inputs of a walk with a controller of the given sizes.
fn record<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    obs: &[Poly],
    goal: Vector2<f64>,
) -> Vec<RecordedInput> {
    walk::<N, NV, NC, NOBS, 8>(obs, goal, 150)
        .into_iter()
        .map(|(c, _)| c)
        .collect()
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
        let config = Config::default().with_budgets_for_horizon(N);
        let mut ctl = Controller::<N, NV, NC, NOBS>::new(config).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            black_box(ctl.step(black_box(&c.input(obs)), None))
        })
    });
}

fn paper(cr: &mut Criterion) {
    const N: usize = 3;
    const NC: usize = constraint_capacity(3, 8, false);
    type Paper = Controller<3, 6, NC, 8>;
    let obs = paper_obstacles::<8>();
    let goal = Vector2::from(PAPER_GOAL);
    let cycles = record::<N, 6, NC, 8>(&obs, goal);
    let mut group = cr.benchmark_group("paper_config");
    group.bench_function("step/warm", |b| {
        let mut ctl = Paper::new(Config::default()).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            black_box(ctl.step(black_box(&c.input(&obs)), None))
        })
    });
    let velocities = moving::VELOCITIES.map(Vector2::from);
    group.bench_function("step/warm-moving", |b| {
        let mut ctl = Paper::new(Config::default()).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            black_box(ctl.step(black_box(&c.input_moving(&obs, &velocities)), None))
        })
    });
    group.bench_function("step/cold", |b| {
        let mut ctl = Paper::new(Config::default()).unwrap();
        let mut i = 0;
        b.iter(|| {
            let c = &cycles[i % cycles.len()];
            i += 1;
            ctl.reset();
            black_box(ctl.step(black_box(&c.input(&obs)), None))
        })
    });
    let ctl = Paper::new(Config::default()).unwrap();
    let qps: Vec<Assembly<3, 6, NC, 8>> = cycles
        .iter()
        .map(|c| {
            let mut a = Assembly::default();
            ctl.assemble(&c.input(&obs), None, &mut a).unwrap();
            a
        })
        .collect();
    group.bench_function("solve/cold", |b| {
        let mut i = 0;
        b.iter(|| {
            let a = &qps[i % qps.len()];
            i += 1;
            black_box(ctl.solver().solve(black_box(&a.qp), &[false; NC]))
        })
    });
    group.finish();
}

fn horizon(cr: &mut Criterion) {
    let obs = paper_obstacles::<8>();
    let goal = Vector2::from(PAPER_GOAL);
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
    bench_step::<20, 40, { constraint_capacity(20, 8, false) }, 8>(
        &mut group,
        BenchmarkId::from_parameter(20),
        &obs,
        goal,
    );
    group.finish();
}

fn obstacles(cr: &mut Criterion) {
    let obs = post_field();
    let goal = Vector2::from(PAPER_GOAL);
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
