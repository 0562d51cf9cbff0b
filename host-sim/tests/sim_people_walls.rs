//! A wall does not move out of the way, a person can: in a 1.6 m corridor
//! with one person (radius 0.25 m) walking head-on at 0.6 m/s, the robot's
//! body and feet never touch a wall (a contact with an obstacle at rest is
//! always the robot's), at delta 0.05 and 0: within the safety relaxation the
//! person's rows give way before the walls' (`controller/src/relax`, "Moving
//! rows first"). Relaxing every safety row alike lets the body into the wall
//! by 3-5 cm here. Every contact is the person's (they walk into the robot
//! giving way, and at y = 0 a foot lands on them while they overlap the body).

use ldcbf_sim::scenario::{LoadOptions, parse_str};
use ldcbf_sim::sim::{ContactCause, Outcome, SimOptions, run};

/// The corridor (walls at |y| >= 0.8 m, obstacles 0 and 1) and the person
/// starting at (5, `y`).
fn corridor(y: f64) -> String {
    format!(
        r#"name = "corridor-headon-person"
description = "1.6 m corridor, one person head-on at 0.6 m/s"
start = {{ x = 0.0, y = 0.0, heading = 0.0 }}
goal = [8.0, 0.0]
time_limit = 40.0

[[obstacles]]
vertices = [[-1.0, 0.8], [9.0, 0.8], [9.0, 1.1], [-1.0, 1.1]]

[[obstacles]]
vertices = [[-1.0, -1.1], [9.0, -1.1], [9.0, -0.8], [-1.0, -0.8]]

[[obstacles]]
regular = {{ center = [5.0, {y}], radius = 0.25, sides = 8 }}
velocity = [-0.6, 0.0]
"#
    )
}

#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "4 closed loops: run with --release (.ci/run does)"
)]
fn corridor_headon_person_robot_never_touches_the_wall() {
    for y in [0.0, 0.1] {
        for delta in ["0.05", "0.0"] {
            let text = corridor(y);
            let opts = LoadOptions::with_sets(&[("controller.delta", delta)]);
            let sc = parse_str(&text, "corridor", &opts).unwrap();
            let sim = run(&sc, SimOptions::default()).unwrap();
            for c in &sim.contacts {
                println!("y {y} delta {delta}: {c:?}");
            }
            let walls: Vec<_> = sim.contacts.iter().filter(|c| c.obstacle < 2).collect();
            assert!(walls.is_empty(), "y {y} delta {delta}: {walls:?}");
            // The robot walks past the person (standing still would pass
            // the check above trivially).
            assert_eq!(sim.outcome, Outcome::GoalReached, "y {y} delta {delta}");
            let robot = sim
                .contacts
                .iter()
                .filter(|c| c.cause == ContactCause::Robot)
                .count();
            println!("y {y} delta {delta}: robot-caused contacts {robot}");
            // The person walks into the robot giving way; a foot that then
            // lands on them while they overlap the body is theirs too
            // (`host-sim/src/sim/contacts.rs`).
            assert_eq!(robot, 0, "y {y} delta {delta}: {:?}", sim.contacts);
        }
    }
}
