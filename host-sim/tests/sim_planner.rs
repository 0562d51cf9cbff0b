//! Global planner (docs/maths.md §5): the `trap` scenario stalls without
//! subgoals and reaches the goal with RRT* subgoals; the maze reaches its goal
//! with them; RRT* is deterministic for a seed and its subgoal path stays clear
//! of the inflated obstacles.
//!
//! Runs in-process with the own QP solver at 20 Hz, no figures.

use ldcbf_controller::closest_point_point_polygon;
use ldcbf_sim::plan::Planner;
use ldcbf_sim::plan::{RrtParams, plan};
use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sim::{Outcome, SimOptions, SimResult, run};
use ldcbf_sim::{Summary, summarize};

fn simulate(name: &str, sets: &[(&str, &str)]) -> (SimResult, Summary) {
    let opts = LoadOptions::with_sets(sets);
    let sc = load(name, &opts).expect("shipped scenario loads");
    let r = run(&sc, SimOptions::default()).expect("simulation starts");
    let s = summarize(&r);
    (r, s)
}

fn assert_no_collision(s: &Summary) {
    let c = s.min_com_clearance.expect("obstacles");
    assert!(
        !s.collision && c >= 0.0,
        "{}: min CoM clearance {c}",
        s.scenario
    );
}

/// Report figure 7: the MPC alone walks into the cup and stalls at its back
/// wall; the loop ends the run as stuck after `stuck_window` without progress.
#[test]
fn trap_stalls_without_the_planner() {
    let (r, s) = simulate("trap", &[]);
    assert_eq!(r.scenario.planner, Planner::None);
    assert_eq!(r.outcome, Outcome::Stuck, "{s:#?}");
    assert!(!s.reached_goal && !s.success);
    assert_no_collision(&s);
    // It stopped inside the cup, in front of the back wall (u in [2.2, 4.2] along
    // the diagonal, |w| < 1.4 across it), well short of the goal.
    let p = r.samples.last().unwrap().position;
    let (u, w) = ((p.x + p.y) / 2f64.sqrt(), (p.y - p.x) / 2f64.sqrt());
    assert!(u > 2.2 && u < 4.2 && w.abs() < 1.4, "stopped at {p:?}");
    assert!(s.final_distance > 2.5, "{}", s.final_distance);
    // "Stuck" is measured from the last 5 cm of progress.
    assert!(s.sim_time >= r.scenario.stuck_window);
}

/// Report figures 8-9: with RRT* subgoals the same layout is solved, walking
/// away from the goal first without being called stuck.
#[test]
fn trap_reaches_the_goal_with_rrt_star() {
    let (r, s) = simulate("trap", &[("planner", "\"rrt_star\"")]);
    assert_eq!(r.outcome, Outcome::GoalReached, "{s:#?}");
    assert!(s.success);
    assert_no_collision(&s);
    assert!(s.planner_error.is_none());
    assert!(s.subgoals >= 2, "at least one via point: {}", s.subgoals);
    assert_eq!(
        s.subgoals_reached, s.subgoals,
        "every subgoal passed in order"
    );
    // The goal distance grew on the way (the detour), which is not "stuck".
    let d0 = (r.scenario.start - r.scenario.goal).norm();
    let dmax = r
        .samples
        .iter()
        .map(|x| (x.position - r.scenario.goal).norm())
        .fold(0.0, f64::max);
    assert!(dmax > d0 - 0.2, "the path leads around the cup");
    // The controller always chased the current subgoal.
    for c in &r.cycles {
        assert_eq!(c.goal, r.navigation.subgoals[c.subgoal]);
    }
}

/// Report 4.2 + 5.1: the maze, a dead end for the MPC alone (see
/// `sim_scenarios.rs`), is solved with subgoals: the scenario as shipped
/// (`run maze`, the README's first command) plans them.
#[test]
fn maze_reaches_the_goal_with_rrt_star() {
    let (r, s) = simulate("maze", &[]);
    assert_eq!(r.scenario.planner, Planner::RrtStar, "maze ships with RRT*");
    assert_eq!(r.outcome, Outcome::GoalReached, "{s:#?}");
    assert!(s.success);
    assert_no_collision(&s);
    assert_eq!(s.subgoals_reached, s.subgoals);
}

#[test]
fn rrt_star_is_deterministic_for_a_seed_and_stays_clear() {
    let sc = load("trap", &LoadOptions::default()).unwrap();
    let params = RrtParams {
        iterations: 800,
        ..sc.rrt.clone()
    };
    let r = sc.robot.body_radius;
    let a = plan((sc.start, sc.goal), &sc.obstacles, &params, r, 11, &|| {
        false
    })
    .unwrap();
    let b = plan((sc.start, sc.goal), &sc.obstacles, &params, r, 11, &|| {
        false
    })
    .unwrap();
    assert_eq!(a.tree.nodes, b.tree.nodes);
    assert_eq!(a.tree.parent, b.tree.parent);
    assert_eq!(a.path, b.path);
    assert_eq!(a.subgoals, b.subgoals);
    assert_eq!(a.cost, b.cost);
    let c = plan((sc.start, sc.goal), &sc.obstacles, &params, r, 12, &|| {
        false
    })
    .unwrap();
    assert_ne!(a.tree.nodes, c.tree.nodes, "another seed, another tree");
    // Every point of the subgoal polyline keeps the body radius plus the margin
    // to the true obstacles, up to half a cell diagonal (the grid's resolution).
    let tol = a.grid.resolution * core::f64::consts::FRAC_1_SQRT_2;
    assert_eq!(a.inflation, r + a.margin_used);
    let mut prev = sc.start;
    for q in &a.subgoals {
        for k in 0..=100 {
            let p = prev + (q - prev) * (f64::from(k) / 100.0);
            for o in &sc.obstacles {
                let d = closest_point_point_polygon(&p, o).signed_distance;
                assert!(d >= a.inflation - tol, "{p:?} is {d} m from an obstacle");
            }
        }
        prev = *q;
    }
    assert_eq!(*a.subgoals.last().unwrap(), sc.goal);
    // The tree's costs follow the report's edge cost through the parents.
    for k in 1..a.tree.nodes.len() {
        let p = a.tree.parent[k].unwrap();
        let n = a.tree.nodes[k];
        let w = (-a.grid.clearance([n.x, n.y]).min(params.clearance_cap)).exp();
        let expect = a.tree.cost[p] + (n - a.tree.nodes[p]).norm() * w;
        assert!((a.tree.cost[k] - expect).abs() < 1e-9);
    }
}

/// A goal the planner cannot reach is not an error of the run: it walks to
/// the goal directly and says why.
#[test]
fn planner_failure_is_reported_and_the_run_goes_on() {
    // A goal in a closed room whose only opening is a 6 cm slit: a point
    // would pass, the 0.5 m body cannot, and every margin down to the body
    // radius alone fails.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("slit.toml");
    let wall = |x0: f64, y0: f64, x1: f64, y1: f64| {
        format!(
            "[[obstacles]]\nvertices = [[{x0}, {y0}], [{x1}, {y0}], [{x1}, {y1}], [{x0}, {y1}]]\n"
        )
    };
    let room = [
        wall(3.0, -2.0, 3.1, -0.03),
        wall(3.0, 0.03, 3.1, 2.0),
        wall(3.0, 2.0, 7.0, 2.1),
        wall(3.0, -2.1, 7.0, -2.0),
        wall(6.9, -2.0, 7.0, 2.0),
    ]
    .concat();
    std::fs::write(
        &file,
        format!(
            "name = \"slit\"\nstart = {{ x = 0.0, y = 0.0 }}\ngoal = [5.0, 0.0]\n\
             planner = \"rrt_star\"\ntime_limit = 20.0\n[rrt_star]\niterations = 300\n{room}"
        ),
    )
    .unwrap();
    let sc = load(file.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let r = run(&sc, SimOptions::default()).expect("simulation starts");
    let s = summarize(&r);
    assert!(r.navigation.plan.is_none());
    let err = s.planner_error.clone().expect("planner failed");
    assert!(err.contains("no path"), "{err}");
    assert_eq!(s.plan_attempts, Some(4), "margins 0.15, 0.075, 0.0375, 0");
    assert!(
        s.planner_fallback
            .as_deref()
            .unwrap()
            .contains("straight at the goal")
    );
    assert_eq!(r.navigation.subgoals, vec![sc.goal]);
    // The body never gets through the slit, nor into the walls.
    assert!(!s.reached_goal && !s.success, "{s:#?}");
    assert!(!s.collision && !s.foot_collision, "{s:#?}");
    assert!(r.samples.iter().all(|p| p.position.x < 3.0));
}
