//! Closed-loop scenario tests (docs/maths.md §4): the shipped scenarios run in-process
//! (no figures) with the own QP solver at 20 Hz, and the plant and the
//! controller's prediction agree.
//!
//! Parameters: the paper's defaults, except where the scenario file says
//! otherwise (its `note` gives the reason): `maze` uses `delta = 0.2`.

use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sim::{Outcome, SimOptions, SimResult, run};
use ldcbf_sim::{Summary, summarize};

/// Largest violation of a cycle's own QP rows tolerated for the applied plans.
const MAX_VIOLATION: f64 = 1e-7;

fn simulate(name: &str) -> (SimResult, Summary) {
    simulate_with(name, &[])
}

fn simulate_with(name: &str, sets: &[(&str, &str)]) -> (SimResult, Summary) {
    let opts = LoadOptions::with_sets(sets);
    let sc = load(name, &opts).expect("shipped scenario loads");
    let r = run(&sc, SimOptions::default()).expect("simulation starts");
    let s = summarize(&r);
    (r, s)
}

fn assert_safe(s: &Summary) {
    let c = s.min_com_clearance.expect("scenario has obstacles");
    assert!(
        !s.collision && c >= 0.0,
        "{}: CoM collision, min clearance {c}",
        s.scenario
    );
    assert!(
        s.max_violation <= MAX_VIOLATION,
        "{}: applied plan violates its rows by {}",
        s.scenario,
        s.max_violation
    );
    assert!(s.max_violation_landed <= s.max_violation);
}

fn assert_reaches_goal(name: &str) -> Summary {
    let (r, s) = simulate(name);
    assert_eq!(r.outcome, Outcome::GoalReached, "{name}: {s:#?}");
    assert!(s.reached_goal && s.success, "{name}: {s:#?}");
    assert!(r.final_distance() <= r.scenario.success_radius + 1e-12);
    assert_safe(&s);
    s
}

#[test]
fn simple_reaches_the_goal_safely() {
    let s = assert_reaches_goal("simple");
    assert_eq!(s.status_counts.get("optimal"), Some(&s.cycles));
}

#[test]
fn circles_reaches_the_goal_safely() {
    assert_reaches_goal("circles");
}

#[test]
fn paper_reaches_the_goal_safely() {
    assert_reaches_goal("paper");
}

/// Without subgoals (`--set planner="none"`; the file uses RRT*) the maze is a
/// dead end for the MPC alone (see the note in `scenarios/maze.toml`): it walks
/// safely, then stops under the wall that separates it from the goal. Reaching
/// the goal as shipped is `sim_planner.rs`'s test.
#[test]
fn maze_walks_safely_into_the_dead_end_without_subgoals() {
    let (r, s) = simulate_with("maze", &[("planner", "\"none\"")]);
    assert_eq!(r.scenario.config.delta, 0.05, "documented override");
    assert_safe(&s);
    assert_eq!(r.outcome, Outcome::Stuck, "{s:#?}");
    assert!(!s.reached_goal);
    // It got past the wedge and up to the wall y = 6 under the goal.
    let last = r.samples.last().unwrap().position;
    assert!(
        last.y > 5.0 && last.y < 6.0 && (last.x - 7.5).abs() < 0.5,
        "{last:?}"
    );
    assert!(s.final_distance > 1.0 && s.final_distance < 2.5);
}

/// The plant (integrated at 1 kHz) and the controller's closed-form prediction
/// agree: every cycle's `x_0` is the plant's CoM state at the end of that step,
/// and every footstep is the target of the last cycle before it landed.
#[test]
fn controller_prediction_matches_the_plant() {
    let (r, _) = simulate("circles");
    let tps = 400usize; // T / dt
    let mut checked = 0;
    for c in &r.cycles {
        let end_tick = (c.step as usize + 1) * tps;
        let Some(s) = r.samples.get(end_tick) else {
            continue;
        };
        let x0 = c.output.plan.x0;
        assert!(
            (x0.position - s.position).amax() < 1e-9,
            "cycle {}",
            c.index
        );
        assert!(
            (x0.velocity - s.velocity).amax() < 1e-9,
            "cycle {}",
            c.index
        );
        checked += 1;
    }
    assert!(checked > 200);
    let landed: Vec<_> = r.cycles.iter().filter(|c| c.landed).collect();
    assert_eq!(landed.len(), r.steps());
    for (f, c) in r.footsteps[1..].iter().zip(&landed) {
        assert_eq!(f.position, c.output.foot_target);
    }
    // Stance sides alternate.
    for w in r.footsteps.windows(2) {
        assert_ne!(w[0].side, w[1].side);
    }
}

/// `--mpc-rate step`: one cycle per step; with an exact plant the plan is the
/// same as at 20 Hz (every cycle of a step predicts the same x_0).
#[test]
fn once_per_step_matches_twenty_hertz_on_an_exact_plant() {
    let sc = load("simple", &LoadOptions::default()).unwrap();
    let a = run(&sc, SimOptions::default()).unwrap();
    let b = run(
        &sc,
        SimOptions {
            mpc_rate: ldcbf_sim::MpcRate::PerStep,
            ..SimOptions::default()
        },
    )
    .unwrap();
    assert_eq!(b.cycles.len(), b.steps() + 1);
    assert!(b.cycles.iter().all(|c| c.time_in_step == 0.0));
    assert_eq!(a.footsteps.len(), b.footsteps.len());
    for (x, y) in a.footsteps.iter().zip(&b.footsteps) {
        assert!((x.position - y.position).amax() < 1e-6);
    }
}

#[test]
fn random_family_runs_from_its_seed() {
    let a = load(
        "random",
        &LoadOptions {
            seed: Some(7),
            sets: vec![],
        },
    )
    .unwrap();
    assert_eq!(a.obstacles.len(), 8);
    assert_eq!(a.seed, 7);
    assert_eq!(
        a.obstacles,
        ldcbf_sim::scenario::random_scenario(7).obstacles
    );
    let r = run(&a, SimOptions::default()).unwrap();
    let s = summarize(&r);
    assert!(s.max_violation <= MAX_VIOLATION);
    assert!(s.cycles > 0);
}
