//! Reference in the loop: the same closed loop with Clarabel
//! (`ldcbf_reference::ClarabelBackend`) instead of the own QP solver gives the
//! same footsteps, to 1e-6 m, on `simple` and `maze`.

use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sim::{SimOptions, Solver, run};

fn compare(name: &str) {
    let sc = load(name, &LoadOptions::default()).unwrap();
    let own = run(&sc, SimOptions::default()).unwrap();
    let cla = run(
        &sc,
        SimOptions {
            solver: Solver::Clarabel,
            ..SimOptions::default()
        },
    )
    .unwrap();
    assert_eq!(own.outcome, cla.outcome, "{name}");
    assert_eq!(own.footsteps.len(), cla.footsteps.len(), "{name}");
    let mut worst = 0.0f64;
    for (a, b) in own.footsteps.iter().zip(&cla.footsteps) {
        assert_eq!(a.side, b.side);
        worst = worst.max((a.position - b.position).amax());
    }
    assert!(worst <= 1e-6, "{name}: footsteps differ by {worst:e} m");
    assert!(cla.cycles.iter().all(|c| c.output.status.is_optimal()));
}

#[test]
fn simple_footsteps_agree_with_clarabel() {
    compare("simple");
}

#[test]
fn maze_footsteps_agree_with_clarabel() {
    compare("maze");
}
