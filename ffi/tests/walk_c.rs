//! The C example `examples/walk.c`, built with the system C compiler against
//! this crate's static library, closes the loop from C; every one of its
//! control cycles (inputs and outputs, as the bits of each double) equals the
//! Rust controller's on the same loop (`ldcbf_nav::fixtures::walk`, the
//! simulator's `RobotController` sizes, the paper's obstacles): bit for bit.
//!
//! Environment:
//! * `CC`: the C compiler (default `cc`).
//! * `LDCBF_WALK_HEX=<file>`: instead of building and running the example,
//!   compare the `walk --hex` output in `<file>` (e.g. the example built for
//!   aarch64 and run under qemu-aarch64, `.ci/embedded.sh`) with the Rust
//!   controller run here.

use std::path::{Path, PathBuf};
use std::process::Command;

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{CommandSource, CycleOutput, QpStatus, Side, constraint_capacity};
use ldcbf_nav::fixtures::{PAPER_GOAL, RecordedInput, paper_obstacles, walk};

/// Steps the C example walks at most (`MAX_STEPS` in walk.c).
const MAX_STEPS: usize = 150;

/// The static library this test was built with: `libldcbf_ffi.a` beside the
/// test executable (cargo builds every crate type of the library into `deps/`).
fn static_lib() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let deps = exe.parent().expect("the test executable is in deps/");
    let lib = deps.join("libldcbf_ffi.a");
    assert!(
        lib.exists(),
        "{} not found: build the library first (cargo test -p ldcbf-ffi builds it)",
        lib.display()
    );
    lib
}

/// Compiles `examples/walk.c` with `$CC` (default `cc`) and returns the binary.
fn build_walk() -> PathBuf {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("walk");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(&cc)
        .args([
            "-std=c11",
            "-O2",
            "-Wall",
            "-Wextra",
            "-Wpedantic",
            "-Werror",
        ])
        .arg("-ffp-contract=off")
        .arg("-I")
        .arg(crate_dir.join("include"))
        .arg(crate_dir.join("examples/walk.c"))
        .arg(static_lib())
        .args(["-lm", "-lpthread", "-ldl"])
        .arg("-o")
        .arg(&out)
        .status()
        .unwrap_or_else(|e| panic!("cannot run the C compiler `{cc}`: {e}"));
    assert!(
        status.success(),
        "compiling examples/walk.c failed: {status}"
    );
    out
}

/// The bits of `x` as walk.c prints them.
fn hex(x: f64) -> String {
    format!(" {:016x}", x.to_bits())
}

/// The C API's code of a command source (`LdcbfCommandSource`), from the
/// Rust enum.
fn source_code(s: CommandSource) -> u32 {
    match s {
        CommandSource::Optimal => 0,
        CommandSource::RelaxedGait => 1,
        CommandSource::RelaxedSafety => 2,
        CommandSource::PreviousPlan => 3,
        CommandSource::CaptureStep => 4,
        CommandSource::Hold => 5,
    }
}

/// The C API's code of a QP status (`LdcbfQpStatus`).
fn qp_code(s: Option<QpStatus>) -> u32 {
    match s {
        None => 0,
        Some(QpStatus::Solved) => 1,
        Some(QpStatus::Infeasible) => 2,
        Some(QpStatus::IterationLimit) => 3,
        Some(QpStatus::NumericalError) => 4,
    }
}

/// One cycle as `walk --hex` prints it.
fn line(i: usize, c: &RecordedInput, o: &CycleOutput<3>) -> String {
    let mut s = format!("cycle {i}");
    for x in [
        c.com_position.x,
        c.com_position.y,
        c.com_velocity.x,
        c.com_velocity.y,
        c.heading,
        c.turning_rate,
        c.stance_foot.x,
        c.stance_foot.y,
    ] {
        s += &hex(x);
    }
    s += match c.stance_side {
        Side::Left => " 0",
        Side::Right => " 1",
    };
    s += &hex(c.time_in_step);
    s += " |";
    for x in [o.foot_target.x, o.foot_target.y, o.turning_rate] {
        s += &hex(x);
    }
    s += &format!(
        " {} {} {} {}",
        o.status.name(),
        source_code(o.info.source),
        qp_code(o.info.qp_status),
        o.info.iterations
    );
    for (f, st) in o.plan.feet.iter().zip(&o.plan.states) {
        for x in [
            f.x,
            f.y,
            st.position.x,
            st.position.y,
            st.velocity.x,
            st.velocity.y,
            st.heading,
        ] {
            s += &hex(x);
        }
    }
    for x in [o.info.cost, o.info.max_violation, o.info.min_h0] {
        s += &hex(x);
    }
    s += &format!(" {} {}", o.info.active_set_size, o.info.active_obstacles);
    s
}

#[test]
fn c_example_walk_equals_rust_controller_bit_for_bit() {
    let text = match std::env::var_os("LDCBF_WALK_HEX") {
        Some(file) => std::fs::read_to_string(&file)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", Path::new(&file).display())),
        None => {
            let walk = build_walk();
            let out = Command::new(&walk)
                .arg("--hex")
                .output()
                .expect("run the C example");
            assert!(
                out.status.success(),
                "walk --hex failed ({}): {}",
                out.status,
                String::from_utf8_lossy(&out.stderr)
            );
            String::from_utf8(out.stdout).expect("walk prints ASCII")
        }
    };

    // The same loop in Rust: RobotController's sizes, obstacles of 32 vertices
    // (the C API's), built as convex hulls of the same points.
    let obstacles = paper_obstacles::<32>();
    let goal = Vector2::new(PAPER_GOAL[0], PAPER_GOAL[1]);
    let rust =
        walk::<3, 6, { constraint_capacity(3, 8, true) }, 8, 32>(&obstacles, goal, MAX_STEPS);
    let expected: Vec<String> = rust
        .iter()
        .enumerate()
        .map(|(i, (c, o))| line(i, c, o))
        .chain([format!("done {}", rust.len())])
        .collect();
    let got: Vec<&str> = text.lines().collect();

    for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
        assert_eq!(*g, e.as_str(), "line {i} differs (C first, Rust second)");
    }
    assert_eq!(
        got.len(),
        expected.len(),
        "C printed {} lines, Rust expects {}",
        got.len(),
        expected.len()
    );
    // The loop really walked: hundreds of cycles, and it ended at the goal.
    let last = rust.last().expect("cycles");
    assert!(rust.len() > 400, "only {} cycles", rust.len());
    let end = last.0.com_position;
    assert!((end - goal).norm() < 0.5, "the walk ended at {end:?}");
    println!(
        "{} cycles equal bit for bit (inputs, command, plan, diagnostics)",
        rust.len()
    );
}
