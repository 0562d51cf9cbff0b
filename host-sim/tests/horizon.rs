//! Closed loops at the long horizons of issue 5 (N = 10 and N = 20, obstacle
//! capacity 8) on the shipped `paper` and `maze` layouts, next to N = 3.
//!
//! The simulator runs only the paper's `PaperController` (N = 3), so the loop is
//! written here, the simulator's in miniature: the LIP is integrated in closed
//! form at 1 kHz (so the CoM clearance is checked at every millisecond), the
//! controller runs at 20 Hz on the exact state, and at each step end (0.4 s)
//! the swing foot lands on the last `foot_target`, the stance side flips and the
//! last `turning_rate` takes effect. Scenario, configuration overrides (the
//! maze's `delta = 0.2`) and, for `maze` with RRT*, the subgoals are the
//! simulator's (`ldcbf_sim::scenario::load`, one `ldcbf_sim::sim::run` for the
//! planner's subgoals).
//!
//! `cargo test --release -p ldcbf-sim --test horizon -- --nocapture` prints one line per run.

use std::time::Instant;

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{CommandSource, Config, Controller, CycleInput, Side, constraint_capacity};
use ldcbf_sim::scenario::{LoadOptions, Scenario, load};
use ldcbf_sim::sim::{SimOptions, run};
use ldcbf_sim::world::clearance;

type V2 = Vector2<f64>;

/// What one closed loop did.
#[derive(Debug, Default)]
struct LoopResult {
    reached: bool,
    steps: u32,
    time: f64,
    /// Smallest signed distance of the 1 kHz CoM samples to any obstacle, m.
    min_clearance: f64,
    cycles: u32,
    optimal: u32,
    relaxed: u32,
    fallback: u32,
    /// Solver iterations per cycle (sorted).
    iterations: Vec<u32>,
    /// Wall time of `step` per cycle, ns (sorted; noisy on a shared machine).
    cycle_ns: Vec<u64>,
    /// Largest row violation of an optimal plan (physical units,
    /// `CycleInfo::max_violation`).
    worst_optimal_violation: f64,
}

fn percentile<T: Copy>(v: &[T], p: f64) -> T {
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// Closed loop from the scenario's start through `subgoals` (the last is the
/// goal) with a controller of horizon `N`, for at most `time_limit` s.
fn closed_loop<const N: usize, const NV: usize, const NC: usize>(
    sc: &Scenario,
    cfg: Config,
    subgoals: &[V2],
    switch_radius: f64,
    time_limit: f64,
) -> LoopResult {
    let mut ctl = Controller::<N, NV, NC, 8>::new(cfg).expect("valid configuration");
    let lip = *ctl.lip();
    let (t_step, ms) = (cfg.step_duration, 1e-3);
    let ticks_per_step = (t_step / ms).round() as u32;
    let (mut p, mut v) = (sc.start, V2::zeros());
    let (mut heading, mut omega) = (sc.start_heading, 0.0);
    let (mut foot, mut side) = (sc.start, sc.stance);
    let (mut target, mut next_omega) = (foot, 0.0);
    let mut current = 0;
    let goal = *subgoals.last().expect("a goal");
    let mut r = LoopResult {
        min_clearance: clearance(&p, &sc.obstacles),
        ..LoopResult::default()
    };
    let mut tick_in_step = 0u32;
    for tick in 0..(time_limit / ms) as u32 {
        if tick % 50 == 0 {
            while current + 1 < subgoals.len() && (p - subgoals[current]).norm() <= switch_radius {
                current += 1;
            }
            let input = CycleInput {
                com_position: p,
                com_velocity: v,
                heading,
                turning_rate: omega,
                stance_foot: foot,
                stance_side: side,
                time_in_step: f64::from(tick_in_step) * ms,
                goal: subgoals[current],
                obstacles: &sc.obstacles,
                obstacle_velocities: &[],
                obstacle_velocity_radii: &[],
                speed_cap: ldcbf_controller::NO_SPEED_CAP,
            };
            let t0 = Instant::now();
            let out = ctl.step(&input, None);
            r.cycle_ns.push(t0.elapsed().as_nanos() as u64);
            r.cycles += 1;
            r.iterations.push(out.info.iterations);
            match out.info.source {
                CommandSource::Optimal => {
                    r.optimal += 1;
                    r.worst_optimal_violation =
                        r.worst_optimal_violation.max(out.info.max_violation);
                }
                CommandSource::RelaxedGait | CommandSource::RelaxedSafety => r.relaxed += 1,
                _ => r.fallback += 1,
            }
            target = out.foot_target;
            next_omega = out.turning_rate;
        }
        (p, v) = lip.propagate(&p, &v, &foot, ms);
        heading += omega * ms;
        tick_in_step += 1;
        r.min_clearance = r.min_clearance.min(clearance(&p, &sc.obstacles));
        if tick_in_step == ticks_per_step {
            tick_in_step = 0;
            foot = target;
            side = match side {
                Side::Left => Side::Right,
                Side::Right => Side::Left,
            };
            omega = next_omega;
            r.steps += 1;
        }
        if current + 1 == subgoals.len() && (p - goal).norm() <= sc.success_radius {
            r.reached = true;
            r.time = f64::from(tick + 1) * ms;
            break;
        }
    }
    if !r.reached {
        r.time = time_limit;
    }
    r.iterations.sort_unstable();
    r.cycle_ns.sort_unstable();
    r
}

fn scenario(name: &str, sets: &[(&str, &str)]) -> Scenario {
    let opts = LoadOptions::with_sets(sets);
    load(name, &opts).expect("shipped scenario loads")
}

/// Iteration budgets for horizon `n` (see `Config::with_budgets_for_horizon`).
fn config_for(base: Config, n: usize) -> Config {
    base.with_budgets_for_horizon(n)
}

fn print(label: &str, n: usize, r: &LoopResult) {
    println!(
        "{label:18} N = {n:2}: reached {:5} in {:6.2} s, {:3} steps; min CoM clearance \
         {:+.3} m; cycles {} (optimal {}, relaxed {}, fallback {}); iterations median {} \
         p99 {} max {}; step time median {:.1} us p99 {:.1} us",
        r.reached,
        r.time,
        r.steps,
        r.min_clearance,
        r.cycles,
        r.optimal,
        r.relaxed,
        r.fallback,
        percentile(&r.iterations, 0.5),
        percentile(&r.iterations, 0.99),
        r.iterations.last().copied().unwrap_or(0),
        percentile(&r.cycle_ns, 0.5) as f64 / 1e3,
        percentile(&r.cycle_ns, 0.99) as f64 / 1e3,
    );
}

/// Runs the three horizons on one scenario and subgoal list.
fn all_horizons(label: &str, sc: &Scenario, subgoals: &[V2], limit: f64) -> [LoopResult; 3] {
    let sw = sc.rrt.switch_radius;
    let r3 = closed_loop::<3, 6, { constraint_capacity(3, 8, true) }>(
        sc,
        config_for(sc.config, 3),
        subgoals,
        sw,
        limit,
    );
    let r10 = closed_loop::<10, 20, { constraint_capacity(10, 8, true) }>(
        sc,
        config_for(sc.config, 10),
        subgoals,
        sw,
        limit,
    );
    let r20 = closed_loop::<20, 40, { constraint_capacity(20, 8, true) }>(
        sc,
        config_for(sc.config, 20),
        subgoals,
        sw,
        limit,
    );
    for (n, r) in [(3, &r3), (10, &r10), (20, &r20)] {
        print(label, n, r);
    }
    [r3, r10, r20]
}

fn assert_safe_and_solved(label: &str, rs: &[LoopResult; 3]) {
    for (n, r) in [3, 10, 20].iter().zip(rs) {
        assert!(
            r.min_clearance >= 0.0,
            "{label} N = {n}: CoM inside an obstacle"
        );
        assert_eq!(r.fallback, 0, "{label} N = {n}: fallback commands");
        assert!(r.worst_optimal_violation <= 1e-9, "{label} N = {n}");
    }
}

#[test]
fn paper_layout_at_long_horizons() {
    let sc = scenario("paper", &[]);
    let rs = all_horizons("paper", &sc, &[sc.goal], 120.0);
    assert_safe_and_solved("paper", &rs);
    for (n, r) in [3, 10, 20].iter().zip(&rs) {
        assert!(r.reached, "paper N = {n}: goal not reached: {r:?}");
    }
}

#[test]
fn maze_at_long_horizons() {
    // Goal-oriented (the scenario as shipped: the MPC alone ends in the dead
    // end under the wall y = 6 at N = 3), and with the RRT* subgoals.
    let sc = scenario("maze", &[]);
    let rs = all_horizons("maze", &sc, &[sc.goal], 80.0);
    assert_safe_and_solved("maze", &rs);

    let sc = scenario("maze", &[("planner", "\"rrt_star\"")]);
    let sim = run(&sc, SimOptions::default()).expect("simulation runs");
    let subgoals = sim.navigation.subgoals.clone();
    assert!(subgoals.len() >= 2, "RRT* subgoals: {subgoals:?}");
    let rs = all_horizons("maze + RRT*", &sc, &subgoals, 120.0);
    assert_safe_and_solved("maze + RRT*", &rs);
    for (n, r) in [3, 10, 20].iter().zip(&rs) {
        assert!(r.reached, "maze + RRT* N = {n}: goal not reached");
    }
}
