//! The moving-obstacle cycles that the Python package must reproduce bit for
//! bit (`python/tests/test_moving.py` reads them): an open-loop walk past
//! three obstacles that move, through the humanoid controller, written as
//! `f64` bits to `python/tests/data/moving_cycles.txt`. This test checks that
//! the file is what the Rust controller computes today;
//! `LDCBF_BLESS=1 cargo test --test moving_fixture` (from the workspace
//! root) rewrites it. The walk and the robot are the C API test's
//! (`ldcbf_nav::fixtures::{open_loop_walk, robot_config}`).

use std::fmt::Write as _;

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{ConvexPolygon, RobotController, Side};
use ldcbf_nav::fixtures::{open_loop_walk, robot_config};

const OBSTACLES: [&[[f64; 2]]; 3] = [
    &[[2.0, 1.0], [3.0, 1.0], [2.5, 2.0]],
    &[[1.0, 3.0], [2.0, 3.0], [2.0, 4.0], [1.0, 4.0]],
    &[[3.5, 3.0], [4.0, 3.5], [3.5, 4.0]],
];
const VELOCITIES: [[f64; 2]; 3] = [[-0.3, -0.2], [0.25, -0.1], [-0.4, 0.35]];

fn hex(x: f64) -> String {
    format!("{:016x}", x.to_bits())
}

/// The fixture file for the obstacles moving at `velocities` (m/s).
fn fixture(velocities: &[Vector2<f64>]) -> String {
    let mut ctl = RobotController::new(robot_config()).unwrap();
    let polys: Vec<ConvexPolygon<16>> = OBSTACLES
        .iter()
        .map(|p| ConvexPolygon::new(p).unwrap())
        .collect();
    let mut s = String::from(
        "# python/tests/test_moving.py: cycles of the humanoid controller (body 0.25 m,\n\
         # feet 0.22 x 0.10 m, foot rows on) with moving obstacles, f64 bits in hex.\n\
         # Written by tests/moving_fixture.rs (LDCBF_BLESS=1); do not edit.\n\
         # obstacle <x y>...; velocity <vx vy> (m/s, one per obstacle);\n\
         # cycle <px py vx vy heading omega footx footy side time_in_step gx gy>\n\
         #   -> <foot_target x y, turning_rate, min_h0, cost> <status> <source>\n",
    );
    for p in OBSTACLES {
        let pts: Vec<String> = p.iter().flat_map(|v| [hex(v[0]), hex(v[1])]).collect();
        writeln!(s, "obstacle {}", pts.join(" ")).unwrap();
    }
    for v in VELOCITIES {
        writeln!(s, "velocity {} {}", hex(v[0]), hex(v[1])).unwrap();
    }
    for i in 0..80u32 {
        let input = open_loop_walk(i).input_moving(&polys, velocities);
        let side = input.stance_side;
        let out = ctl.step(&input, None);
        let ins = [
            input.com_position.x,
            input.com_position.y,
            input.com_velocity.x,
            input.com_velocity.y,
            input.heading,
            input.turning_rate,
            input.stance_foot.x,
            input.stance_foot.y,
            if side == Side::Left { 0.0 } else { 1.0 },
            input.time_in_step,
            input.goal.x,
            input.goal.y,
        ];
        let outs = [
            out.foot_target.x,
            out.foot_target.y,
            out.turning_rate,
            out.info.min_h0,
            out.info.cost,
        ];
        let ins: Vec<String> = ins.into_iter().map(hex).collect();
        let outs: Vec<String> = outs.into_iter().map(hex).collect();
        writeln!(
            s,
            "cycle {} -> {} {} {}",
            ins.join(" "),
            outs.join(" "),
            out.status.name(),
            out.info.source.name()
        )
        .unwrap();
    }
    s
}

#[test]
fn the_python_fixture_is_the_rust_controllers() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("python/tests/data/moving_cycles.txt");
    let now = fixture(&VELOCITIES.map(Vector2::from));
    if std::env::var_os("LDCBF_BLESS").is_some() {
        std::fs::write(&path, &now).unwrap();
    }
    let stored = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (LDCBF_BLESS=1 writes it)", path.display()));
    assert!(
        stored == now,
        "{} is not today's output (LDCBF_BLESS=1 rewrites it)",
        path.display()
    );
    // The motion matters: most commands differ from those of the same walk
    // with the obstacles at rest.
    let at_rest = fixture(&[]);
    let cycles = |s: &str| -> Vec<String> {
        s.lines()
            .filter(|l| l.starts_with("cycle"))
            .map(String::from)
            .collect()
    };
    let differ = cycles(&now)
        .iter()
        .zip(cycles(&at_rest))
        .filter(|(a, b)| **a != *b)
        .count();
    assert!(differ > 40, "{differ} of 80 cycles differ");
}
