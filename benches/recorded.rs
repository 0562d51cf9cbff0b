//! Benchmarks of the controller on control cycles recorded from simulator runs
//! (issue 5, items 1 and 3), at the paper's configuration
//! (`RobotController`: N = 3, capacity 8 obstacles, row capacity 72).
//!
//! # The recorded sets
//!
//! Each set is closed loops of `ldcbf-sim` run in-process exactly as
//! `ldcbf-sim deadline` runs them (own solver, 20 Hz, the scenario's own
//! configuration, e.g. `maze`'s `delta = 0.2`), before any timing; their
//! cycle inputs are rebuilt from the logs by `ldcbf_sim::studies::replay` and checked
//! to reproduce every logged output bit for bit (`Recording::verify`), so the
//! benchmarks replay exactly the simulator's cycles:
//!
//! * `maze`: the runs `maze+none` (no subgoals; the walk ends stuck in the
//!   dead end after about 63 s, many cycles pressed against walls) and
//!   `maze+rrt_star` (the scenario as shipped);
//! * `paper`: the run `paper`;
//! * `random`: the runs `random@0` .. `random@9` (seeds 0..9 of the paper's
//!   random family, known map).
//!
//! # Criterion benchmarks (group `sim_<set>`)
//!
//! * `step/warm`: `Controller::step` on the set's cycles in order, one
//!   controller per run carrying its warm start from cycle to cycle as in the
//!   loop (reset at the start of each run);
//! * `step/cold`: the same with `Controller::reset` before every cycle (no warm
//!   start, no previous plan);
//! * `solve/warm`, `solve/cold`: `DualActiveSet::solve` alone on the same
//!   cycles' nominal QPs (assembled once, before timing, by the controller as
//!   it ran: captured at its first solver call of each cycle), with the
//!   warm-start rows the controller marked for it, or none. Each QP is copied
//!   into one workspace before the timer starts (the controller solves the QP
//!   it just assembled, in cache), so the timer runs around each call
//!   (`iter_custom`), its floor (printed, about 20-30 ns) included.
//!
//! One criterion iteration is one cycle; the iterations of a sample walk
//! through the set in order, so criterion's estimate is the MEAN time per cycle
//! over the set (its "median" is the median of the per-sample means).
//!
//! # Per-cycle table (printed first)
//!
//! For the median per cycle and the worst recorded cycle, every cycle is timed
//! individually: `R` passes over the set in order (each pass exactly as above,
//! `Instant` around each call only), and each cycle's time is its minimum over
//! the passes (a preemption or a cache miss of one pass does not count; a cycle
//! that is slow in every pass does). Printed per set and mode: mean (to compare
//! with criterion's estimate), median, p99 and max over the cycles of those
//! minima, the worst cycle (run, index, status, iterations, active obstacles),
//! the max over the optimal cycles only, and, less optimistic, the mean and the
//! max over the cycles of each cycle's MEDIAN over the passes (a preemption
//! must then hit half of a cycle's passes to count). `R` is `RECORDED_PASSES` (default 50; 0
//! skips the table); under `cargo test --benches` (no `--bench` argument) one
//! pass. `cargo bench --bench recorded -- none` prints the table alone (the
//! filter matches no benchmark).
//!
//! Plots off, as in `benches/controller.rs`.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::Criterion;
use ldcbf_controller::{
    CycleInput, CycleOutput, CycleStatus, DenseQp, DualActiveSet, QpBackend, QpSolution,
    RobotController,
};
use ldcbf_sim::report::compute_stats;
use ldcbf_sim::sim::{HORIZON, NC, NV};
use ldcbf_sim::studies::deadline::{Case, random_cases};
use ldcbf_sim::studies::replay::{Recording, record_case};
use ldcbf_sim::world::MAX_VERTICES;

/// Seeds of the `random` set.
const RANDOM_SEEDS: u64 = 10;

/// Default number of timed passes of the per-cycle table.
const DEFAULT_PASSES: usize = 50;

/// The targets for a full cycle at the paper's configuration, ns.
const TARGET_MEDIAN_NS: u64 = 3_000;
const TARGET_WORST_NS: u64 = 15_000;

/// A backend that solves with the own solver and keeps the first QP of the
/// cycle (the nominal one) with its warm-start marks.
#[derive(Default)]
struct Capture {
    first: Option<(DenseQp<NV, NC>, [bool; NC])>,
}

impl QpBackend<NV, NC> for Capture {
    fn solve_qp(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        prefer: &[bool; NC],
    ) -> QpSolution<NV, NC> {
        if self.first.is_none() {
            self.first = Some((qp.clone(), *prefer));
        }
        solver.solve(qp, prefer)
    }
}

/// One recorded cycle's nominal QP.
struct Qp {
    /// Index of the run in the set.
    run: usize,
    /// Cycle index in the run.
    cycle: usize,
    qp: DenseQp<NV, NC>,
    prefer: [bool; NC],
}

/// The QP being solved, in one place in memory, as in the controller (which
/// assembles each cycle's QP into the same workspace and solves it there while
/// it is in cache). Solving the stored QPs in place would instead read each
/// from memory (a set's QPs are several MB), a cost the controller does not
/// have; the copy is made before the timer starts.
struct Workspace {
    qp: DenseQp<NV, NC>,
    prefer: [bool; NC],
}

impl Default for Workspace {
    fn default() -> Self {
        Workspace {
            qp: DenseQp::default(),
            prefer: [false; NC],
        }
    }
}

impl Workspace {
    /// Copies `q`'s QP, and its warm-start marks if `warm` (else none).
    fn load(&mut self, q: &Qp, warm: bool) {
        self.qp.clone_from(&q.qp);
        self.prefer = if warm { q.prefer } else { [false; NC] };
    }
}

/// A recorded set: its runs, their controllers and QPs.
struct Set {
    name: &'static str,
    runs: Vec<Recording>,
    /// One controller per run, with the run's configuration (its solver
    /// holds the run's `max_iter`).
    controllers: Vec<RobotController>,
    qps: Vec<Qp>,
}

impl Set {
    fn record(name: &'static str, cases: &[Case]) -> Set {
        let runs: Vec<Recording> = cases
            .iter()
            .map(|c| {
                let r = record_case(c, &[]).unwrap_or_else(|e| panic!("{e:#}"));
                r.verify().unwrap_or_else(|e| panic!("{e:#}"));
                r
            })
            .collect();
        let controllers: Vec<RobotController> = runs
            .iter()
            .map(|r| r.controller().expect("config"))
            .collect();
        let mut qps = Vec::new();
        for (k, r) in runs.iter().enumerate() {
            let mut ctl = RobotController::<Capture>::with_backend(r.config, Capture::default())
                .expect("config");
            for i in 0..r.len() {
                let out = ctl.step(&r.input(i).expect("input"), None);
                assert_eq!(format!("{out:?}"), format!("{:?}", r.outputs[i]));
                if let Some((qp, prefer)) = ctl.backend_mut().first.take() {
                    qps.push(Qp {
                        run: k,
                        cycle: i,
                        qp,
                        prefer,
                    });
                }
            }
        }
        Set {
            name,
            runs,
            controllers,
            qps,
        }
    }

    fn cycles(&self) -> usize {
        self.runs.iter().map(Recording::len).sum()
    }

    /// Every cycle's input, in order, with its run index.
    fn inputs(&self) -> Vec<(usize, usize, CycleInput<'_, MAX_VERTICES>)> {
        self.runs
            .iter()
            .enumerate()
            .flat_map(|(k, r)| (0..r.len()).map(move |i| (k, i, r.input(i).expect("input"))))
            .collect()
    }

    fn output(&self, run: usize, cycle: usize) -> &CycleOutput<HORIZON> {
        &self.runs[run].outputs[cycle]
    }
}

fn sets() -> Vec<Set> {
    let parse = |s: &str| s.parse::<Case>().expect("case");
    vec![
        Set::record("maze", &[parse("maze+none"), parse("maze+rrt_star")]),
        Set::record("paper", &[parse("paper")]),
        Set::record("random", &random_cases(RANDOM_SEEDS)),
    ]
}

/// The four modes, timed per call.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    StepWarm,
    StepCold,
    SolveWarm,
    SolveCold,
}

impl Mode {
    const ALL: [Mode; 4] = [
        Mode::StepWarm,
        Mode::StepCold,
        Mode::SolveWarm,
        Mode::SolveCold,
    ];

    fn name(self) -> &'static str {
        match self {
            Mode::StepWarm => "step/warm",
            Mode::StepCold => "step/cold",
            Mode::SolveWarm => "solve/warm",
            Mode::SolveCold => "solve/cold",
        }
    }
}

/// One pass over the set in `mode`, each call timed: (run, cycle, ns) in order.
fn timed_pass(set: &Set, mode: Mode, ctls: &mut [RobotController]) -> Vec<(usize, usize, u64)> {
    match mode {
        Mode::StepWarm | Mode::StepCold => set
            .inputs()
            .into_iter()
            .map(|(k, i, input)| {
                if i == 0 || mode == Mode::StepCold {
                    ctls[k].reset();
                }
                let t0 = Instant::now();
                let out = ctls[k].step(black_box(&input), None);
                let ns = t0.elapsed().as_nanos();
                black_box(out);
                (k, i, u64::try_from(ns).unwrap_or(u64::MAX))
            })
            .collect(),
        Mode::SolveWarm | Mode::SolveCold => {
            let mut ws = Workspace::default();
            set.qps
                .iter()
                .map(|q| {
                    ws.load(q, mode == Mode::SolveWarm);
                    let solver = set.controllers[q.run].solver();
                    let t0 = Instant::now();
                    let sol = solver.solve(black_box(&ws.qp), &ws.prefer);
                    let ns = t0.elapsed().as_nanos();
                    black_box(sol);
                    (q.run, q.cycle, u64::try_from(ns).unwrap_or(u64::MAX))
                })
                .collect()
        }
    }
}

/// Smallest measurable interval of `Instant` here (min over many empty pairs), ns.
fn timer_floor() -> u64 {
    (0..10_000)
        .map(|_| {
            let t0 = Instant::now();
            u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX)
        })
        .min()
        .unwrap_or(0)
}

/// The per-cycle table (see the module docs).
fn per_cycle_table(sets: &[Set], passes: usize) {
    println!(
        "\nPer-cycle times: min over {passes} passes per cycle, then over the cycles \
         (Instant floor {} ns, included)\n",
        timer_floor()
    );
    println!(
        "| set | mode | cycles | mean ns | p50 ns | p99 ns | max ns | worst cycle | max optimal ns | medians: mean / max ns | targets (p50 <= {} ns, max <= {} ns) |",
        TARGET_MEDIAN_NS, TARGET_WORST_NS
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for set in sets {
        for mode in Mode::ALL {
            let mut ctls: Vec<RobotController> = set
                .runs
                .iter()
                .map(|r| r.controller().expect("config"))
                .collect();
            // Per cycle: (run, cycle, every pass's time).
            let mut all: Vec<(usize, usize, Vec<u64>)> = Vec::new();
            for p in 0..passes {
                let pass = timed_pass(set, mode, &mut ctls);
                if p == 0 {
                    all = pass.into_iter().map(|(k, i, t)| (k, i, vec![t])).collect();
                } else {
                    for (a, t) in all.iter_mut().zip(pass) {
                        a.2.push(t.2);
                    }
                }
            }
            let best: Vec<(usize, usize, u64)> = all
                .iter()
                .map(|(k, i, t)| (*k, *i, t.iter().copied().min().unwrap_or(0)))
                .collect();
            let medians: Vec<u64> = all
                .iter()
                .map(|(_, _, t)| compute_stats(t).p50_ns)
                .collect();
            let medians = compute_stats(&medians);
            let ns: Vec<u64> = best.iter().map(|b| b.2).collect();
            let st = compute_stats(&ns);
            let Some(&(wk, wi, wns)) = best.iter().max_by_key(|b| b.2) else {
                continue;
            };
            let w = set.output(wk, wi);
            let optimal: Vec<u64> = best
                .iter()
                .filter(|b| set.output(b.0, b.1).status == CycleStatus::Optimal)
                .map(|b| b.2)
                .collect();
            let max_opt = optimal.iter().copied().max().unwrap_or(0);
            let targets = if matches!(mode, Mode::StepWarm | Mode::StepCold) {
                let m = if st.p50_ns <= TARGET_MEDIAN_NS {
                    "p50 met"
                } else {
                    "p50 MISSED"
                };
                let x = if st.max_ns <= TARGET_WORST_NS {
                    "max met"
                } else {
                    "max MISSED"
                };
                format!("{m}, {x}")
            } else {
                "-".into()
            };
            println!(
                "| {} | {} | {} | {:.0} | {} | {} | {} | {} #{} ({}, {} it, {} obst.) {} ns | {} ({} cycles) | {:.0} / {} | {} |",
                set.name,
                mode.name(),
                ns.len(),
                st.mean_ns,
                st.p50_ns,
                st.p99_ns,
                st.max_ns,
                set.runs[wk].label,
                wi,
                w.status.name(),
                w.info.iterations,
                w.info.active_obstacles,
                wns,
                max_opt,
                optimal.len(),
                medians.mean_ns,
                medians.max_ns,
                targets
            );
        }
    }
    for set in sets {
        let outs = set.runs.iter().flat_map(|r| r.outputs.iter());
        let non_opt = outs.clone().filter(|o| !o.status.is_optimal()).count();
        let max_obst = outs.map(|o| o.info.active_obstacles).max().unwrap_or(0);
        println!(
            "{}: {} runs, {} cycles ({} not optimal), {} QPs, at most {} active obstacles",
            set.name,
            set.runs.len(),
            set.cycles(),
            non_opt,
            set.qps.len(),
            max_obst
        );
    }
    println!();
}

fn bench_set(cr: &mut Criterion, set: &Set) {
    let inputs = set.inputs();
    let mut group = cr.benchmark_group(format!("sim_{}", set.name));
    for mode in [Mode::StepWarm, Mode::StepCold] {
        group.bench_function(mode.name(), |b| {
            let mut ctls: Vec<RobotController> = set.controllers.clone();
            let mut n = 0usize;
            b.iter(|| {
                let (k, i, input) = &inputs[n];
                n = if n + 1 == inputs.len() { 0 } else { n + 1 };
                if *i == 0 || mode == Mode::StepCold {
                    ctls[*k].reset();
                }
                black_box(ctls[*k].step(black_box(input), None))
            })
        });
    }
    for mode in [Mode::SolveWarm, Mode::SolveCold] {
        group.bench_function(mode.name(), |b| {
            let mut ws = Workspace::default();
            let mut n = 0usize;
            // Only the solve is timed: the copy into the workspace is not (see
            // `Workspace`), so the timer runs around each call.
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let q = &set.qps[n];
                    n = if n + 1 == set.qps.len() { 0 } else { n + 1 };
                    ws.load(q, mode == Mode::SolveWarm);
                    let solver = set.controllers[q.run].solver();
                    let t0 = Instant::now();
                    let sol = solver.solve(black_box(&ws.qp), &ws.prefer);
                    total += t0.elapsed();
                    black_box(sol);
                }
                total
            })
        });
    }
    group.finish();
}

fn main() {
    let bench_mode = std::env::args().any(|a| a == "--bench");
    let listing = std::env::args().any(|a| a == "--list");
    let passes = if bench_mode {
        std::env::var("RECORDED_PASSES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(DEFAULT_PASSES)
    } else {
        1
    };
    let sets = sets();
    if passes > 0 && !listing {
        per_cycle_table(&sets, passes);
    }
    // Plots off: the workspace's plotters is built without system fonts (for the
    // simulator's figures), which criterion's own plots would need.
    let mut cr = Criterion::default().without_plots().configure_from_args();
    for set in &sets {
        bench_set(&mut cr, set);
    }
    cr.final_summary();
}
