//! The Cortex-M7 firmware (`firmware/`, its own crate for `thumbv7em-none-eabihf`)
//! against the host, under QEMU.
//!
//! * `firmware_matches_host_in_qemu` builds the firmware, runs it twice in
//!   `qemu-system-arm -M mps2-an500 -icount shift=5` and checks: both runs print
//!   exactly the same lines (the instruction counts are deterministic); every
//!   command (`foot_target`, `turning_rate`) equals the host's to 1e-9 and every
//!   status is the host's, the host replaying the same recorded cycles in the
//!   same order (the warm start carries across cycles); the instructions per
//!   cycle, flash and RAM stay within the ceilings of [`budgets`], and it prints
//!   which of the targets are met. It writes the instructions per
//!   cycle to `firmware/target/instructions.csv` (header
//!   `cycle,status,iterations,instructions`, read by `ldcbf-sim deadline
//!   --instructions`). It needs `qemu-system-arm` and the
//!   `thumbv7em-none-eabihf` target and fails if either is missing, so it is
//!   `#[ignore]`d in the plain `cargo test` and run by `.ci/embedded.sh`.
//! * `regenerate_recorded_cycles` rewrites `firmware/src/recorded.rs` from the
//!   closed loop below (run by hand, see `firmware/README.md`).

use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Duration;

use ldcbf_controller::nalgebra::{SVector, Vector2};
use ldcbf_controller::qp::{DenseQp, DualActiveSet, QpBackend, QpSolution, Reprobe};
use ldcbf_controller::{
    Config, Controller, ConvexPolygon, CycleStatus, PaperController, RecordedInput,
    constraint_capacity,
};
use ldcbf_nav::fixtures::{PAPER_GOAL, PAPER_OBSTACLES, paper_obstacles, walk};
use ldcbf_sim::studies::deadline::INSTRUCTIONS_HEADER;

mod recorded {
    include!("../firmware/src/recorded.rs");
}

mod moving {
    include!("../firmware/src/moving.rs");
}

#[path = "firmware_qemu/qemu.rs"]
mod qemu;
use qemu::{FirmwareCycle, build_firmware, elf_sizes, parse_run, run_qemu};

/// The targets of the issue: instructions per control cycle at N = 3 (0.25 ms
/// at 400 MHz, one instruction per clock), flash 64 KiB, RAM 16 KiB. Each is
/// reported as met or not; the test enforces the ceilings of [`budgets`]:
/// the target where it is met (today: all of them, see firmware/README.md)
/// and, where one is not, a ceiling above today's value so that gross
/// regressions still fail.
const TARGET_INSTRUCTIONS: u64 = 100_000;
const TARGET_FLASH: u64 = 64 * 1024;
const TARGET_RAM: u64 = 16 * 1024;
/// The enforced ceiling of the walk-into pass, instructions per cycle: the
/// target, met there (firmware/README.md).
const WALK_INTO_CEILING: u64 = 100_000;
/// Commands must agree with the host's to this (m, rad/s).
const COMMAND_TOL: f64 = 1e-9;
/// `-icount` shift: one instruction = 2^ICOUNT_SHIFT ns of virtual time.
const ICOUNT_SHIFT: u32 = 5;
/// SysTick period on `mps2-an500` (25 MHz processor clock), ns.
const SYSTICK_NS: f64 = 40.0;
/// Wall-clock limit of one QEMU run.
const QEMU_TIMEOUT: Duration = Duration::from_secs(120);

/// Cycles kept in `recorded.rs`.
const RECORDED_CYCLES: usize = 240;
/// Index of the first cycle of the third pass (people walking into the path).
const WALK_INTO_START: usize = 2 * RECORDED_CYCLES;

type Poly = ConvexPolygon<8>;

fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A recorded cycle: `[p_x, p_y, v_x, v_y, heading, omega, foot_x, foot_y,
/// time_in_step, side]` as `f64` bits (side: 0 left, 1 right;
/// [`RecordedInput::to_bits`]).
type Row = [u64; 10];

/// The shared closed loop (`ldcbf_nav::fixtures::walk`, as in the benchmarks):
/// every cycle's input and the controller's iterations for it.
fn closed_loop(obstacles: &[Poly], goal: Vector2<f64>) -> Vec<(Row, u32)> {
    walk::<3, 6, NC, 8, 8>(obstacles, goal, 150)
        .iter()
        .map(|(c, out)| (c.to_bits(), out.info.iterations))
        .collect()
}

/// What the host computes for one recorded cycle.
#[derive(Clone, Copy, Debug)]
struct HostCommand {
    foot: [f64; 2],
    turning_rate: f64,
    status: CycleStatus,
    iterations: u32,
}

/// Replays the recorded cycles in order through one controller (as the
/// firmware), the obstacles moving at `velocities` (m/s; empty: at rest).
fn host_replay(
    rows: &[Row],
    goal: Vector2<f64>,
    obstacles: &[Poly],
    velocities: &[Vector2<f64>],
) -> Vec<HostCommand> {
    let mut ctl = PaperController::new(Config::default()).expect("valid config");
    rows.iter()
        .map(|r| {
            let out = ctl.step(
                &RecordedInput::from_bits(r, goal).input_moving(obstacles, velocities),
                None,
            );
            HostCommand {
                foot: [out.foot_target.x, out.foot_target.y],
                turning_rate: out.turning_rate,
                status: out.status,
                iterations: out.info.iterations,
            }
        })
        .collect()
}

/// A [`QpBackend`] that counts the solves of a cycle and their iterations.
#[derive(Default)]
struct CountSolves(Vec<u32>);

const NC: usize = constraint_capacity(3, 8, false);

impl QpBackend<6, NC> for CountSolves {
    fn solve_qp(
        &mut self,
        solver: &DualActiveSet<6, NC>,
        qp: &DenseQp<6, NC>,
        prefer: &[bool; NC],
    ) -> QpSolution<6, NC> {
        let sol = solver.solve(qp, prefer);
        self.0.push(sol.iterations);
        sol
    }

    fn solve_reprobe(
        &mut self,
        solver: &DualActiveSet<6, NC>,
        qp: &DenseQp<6, NC>,
        h: &SVector<f64, NC>,
        enabled: &[bool; NC],
        prefer: &[bool; NC],
        budget: u32,
        state: &mut Reprobe<6, NC>,
    ) -> QpSolution<6, NC> {
        let sol = solver.solve_reprobe(qp, h, enabled, prefer, budget, state);
        self.0.push(sol.iterations);
        sol
    }
}

/// Where the third pass's infeasible cycles spend their solves (run by hand,
/// firmware/README.md): the host replays the walk-into pass as the firmware
/// does and prints, per infeasible cycle, the command's source, the
/// iterations and each solve's iterations (the nominal solve first).
#[test]
#[ignore = "diagnostic print-out; run by hand (firmware/README.md)"]
fn walk_into_solves() {
    let obstacles = paper_obstacles::<8>();
    let goal = Vector2::from(recorded::GOAL);
    let into = moving::WALK_INTO.map(Vector2::from);
    let mut ctl = Controller::<3, 6, NC, 8, CountSolves>::with_backend(
        Config::default(),
        CountSolves::default(),
    )
    .expect("valid config");
    let mut per_cycle = Vec::new();
    for (k, r) in recorded::CYCLES.iter().enumerate() {
        ctl.backend_mut().0.clear();
        let input = RecordedInput::from_bits(r, goal).input_moving(&obstacles, &into);
        let out = ctl.step(&input, None);
        let solves = &ctl.backend().0;
        if out.status != CycleStatus::Optimal {
            println!(
                "cycle {k}: {:?} {:?}, {} iterations, {} solves {solves:?}",
                out.status,
                out.info.source,
                out.info.iterations,
                solves.len()
            );
            per_cycle.push((solves.len(), out.info.iterations));
        }
    }
    let total: usize = per_cycle.iter().map(|(s, _)| s).sum();
    println!(
        "{} infeasible cycles, {total} solves (the nominal ones included)",
        per_cycle.len()
    );
    assert!(
        !per_cycle.is_empty(),
        "the walk-into pass has infeasible cycles"
    );
}

/// The `RECORDED_CYCLES` consecutive cycles of the closed loop with the most
/// solver iterations (the hardest stretch: obstacles close by); first such
/// window on ties.
fn hardest_window(all: &[(Row, u32)]) -> std::ops::Range<usize> {
    let n = RECORDED_CYCLES.min(all.len());
    let total = |s: usize| -> u64 { all[s..s + n].iter().map(|(_, it)| u64::from(*it)).sum() };
    let start = (0..=all.len() - n)
        .max_by_key(|&s| (total(s), std::cmp::Reverse(s)))
        .unwrap_or(0);
    start..start + n
}

#[test]
#[ignore = "rewrites firmware/src/recorded.rs; run by hand (firmware/README.md)"]
fn regenerate_recorded_cycles() {
    let obstacles = paper_obstacles::<8>();
    let goal = Vector2::from(PAPER_GOAL);
    let all = closed_loop(&obstacles, goal);
    let window = hardest_window(&all);
    let rows: Vec<Row> = all[window.clone()].iter().map(|(r, _)| *r).collect();

    let mut s = String::new();
    let f = &mut s;
    writeln!(
        f,
        "// @generated by tests/firmware_qemu.rs (`regenerate_recorded_cycles`); do not edit."
    )
    .unwrap();
    writeln!(
        f,
        "// Closed loop of the `paper` scenario: start (0, 0), goal (10, 10), controller"
    )
    .unwrap();
    writeln!(
        f,
        "// at 20 Hz, {} cycles in all; kept: cycles {}..{}, the {} consecutive cycles",
        all.len(),
        window.start,
        window.end,
        rows.len()
    )
    .unwrap();
    writeln!(
        f,
        "// with the most solver iterations. Shared by the firmware and the host test."
    )
    .unwrap();
    writeln!(f).unwrap();
    writeln!(f, "/// Goal of every recorded cycle, m.").unwrap();
    writeln!(f, "pub const GOAL: [f64; 2] = {PAPER_GOAL:?};").unwrap();
    writeln!(f).unwrap();
    writeln!(
        f,
        "/// Obstacle point sets (both sides take their convex hulls), m."
    )
    .unwrap();
    writeln!(
        f,
        "pub const OBSTACLES: [&[[f64; 2]]; {}] = [",
        PAPER_OBSTACLES.len()
    )
    .unwrap();
    for o in PAPER_OBSTACLES {
        writeln!(f, "    &{o:?},").unwrap();
    }
    writeln!(f, "];").unwrap();
    writeln!(f).unwrap();
    writeln!(
        f,
        "/// Recorded cycle inputs, to be replayed in order: `[p_x, p_y, v_x, v_y, heading,"
    )
    .unwrap();
    writeln!(
        f,
        "/// omega, foot_x, foot_y, time_in_step, side]` as `f64` bits (side 0 = left,"
    )
    .unwrap();
    writeln!(f, "/// 1 = right stance foot).").unwrap();
    writeln!(f, "#[rustfmt::skip]").unwrap();
    writeln!(f, "pub static CYCLES: [[u64; 10]; {}] = [", rows.len()).unwrap();
    for (k, r) in rows.iter().enumerate() {
        let c = RecordedInput::from_bits(r, goal);
        let mut fields: Vec<String> = r[..9].iter().map(|b| format!("{b:#018x}")).collect();
        fields.push(r[9].to_string());
        writeln!(
            f,
            "    [{}], // {}: p = ({:.3}, {:.3})",
            fields.join(", "),
            window.start + k,
            c.com_position.x,
            c.com_position.y
        )
        .unwrap();
    }
    writeln!(f, "];").unwrap();
    let path = workspace_root().join("firmware/src/recorded.rs");
    std::fs::write(&path, s).expect("write recorded.rs");
    println!(
        "wrote {} cycles ({}..{} of {}) to {}",
        rows.len(),
        window.start,
        window.end,
        all.len(),
        path.display()
    );
}

#[test]
#[ignore = "needs qemu-system-arm and the thumbv7em-none-eabihf target; run by .ci/embedded.sh"]
fn firmware_matches_host_in_qemu() {
    let elf = build_firmware();

    // Determinism: two runs print exactly the same, instruction counts included.
    let first = run_qemu(&elf);
    let second = run_qemu(&elf);
    assert!(
        first == second,
        "two QEMU runs of the same firmware printed different output (not deterministic)"
    );
    let run = parse_run(&first);

    // The commands equal the host's: same recorded cycles, same order.
    assert_eq!(recorded::GOAL, PAPER_GOAL, "recorded.rs goal");
    assert_eq!(
        recorded::OBSTACLES,
        PAPER_OBSTACLES,
        "recorded.rs obstacles"
    );
    // Same point sets as checked above, so the shared polygons are the firmware's.
    let obstacles = paper_obstacles::<8>();
    let goal = Vector2::from(recorded::GOAL);
    // First pass at rest; second and third (each after a reset) with the
    // obstacles moving away from the recorded path and walking into it.
    let away = moving::VELOCITIES.map(Vector2::from);
    let into = moving::WALK_INTO.map(Vector2::from);
    let mut host = host_replay(&recorded::CYCLES, goal, &obstacles, &[]);
    host.extend(host_replay(&recorded::CYCLES, goal, &obstacles, &away));
    host.extend(host_replay(&recorded::CYCLES, goal, &obstacles, &into));
    assert_eq!(run.cycles.len(), host.len(), "cycles replayed");
    let mut worst = 0.0f64;
    let mut iteration_mismatches = 0;
    let mut failures = Vec::new();
    for (k, (fw, h)) in run.cycles.iter().zip(&host).enumerate() {
        assert_eq!(fw.index, k, "cycle order");
        let diff = (fw.foot[0] - h.foot[0])
            .abs()
            .max((fw.foot[1] - h.foot[1]).abs())
            .max((fw.turning_rate - h.turning_rate).abs());
        worst = worst.max(diff);
        if diff.is_nan() || diff > COMMAND_TOL || fw.status != h.status.name() {
            failures.push(format!(
                "cycle {k}: firmware foot {:?} omega {:e} {} / host foot {:?} omega {:e} {} \
                 (diff {diff:e})",
                fw.foot,
                fw.turning_rate,
                fw.status,
                h.foot,
                h.turning_rate,
                h.status.name()
            ));
        }
        iteration_mismatches += usize::from(fw.iterations != h.iterations);
    }
    assert!(
        failures.is_empty(),
        "{} of {} commands differ from the host's by more than {COMMAND_TOL:e} or in status:\n{}",
        failures.len(),
        host.len(),
        failures.join("\n")
    );

    // Instructions per cycle: ticks of the 25 MHz SysTick, 2^shift ns per
    // instruction; checked against 256 `nop`s.
    let ticks_per_instruction = f64::from(1u32 << ICOUNT_SHIFT) / SYSTICK_NS;
    let nop = (run.nop256_ticks - run.empty_ticks) as f64 / 256.0;
    assert!(
        (nop - ticks_per_instruction).abs() <= 0.01 * ticks_per_instruction,
        "calibration: 256 nops took {} ticks, {nop} per instruction, expected {ticks_per_instruction}",
        run.nop256_ticks - run.empty_ticks
    );
    let instructions = |c: &FirmwareCycle| {
        (c.ticks.saturating_sub(run.empty_ticks) as f64 / ticks_per_instruction).round() as u64
    };
    let stats = |pick: &dyn Fn(&FirmwareCycle) -> bool| {
        let mut v: Vec<u64> = run
            .cycles
            .iter()
            .filter(|c| pick(c))
            .map(instructions)
            .collect();
        v.sort_unstable();
        let median = if v.is_empty() {
            0
        } else {
            v[(v.len() - 1) / 2]
        };
        (v.len(), median, v.last().copied().unwrap_or(0))
    };
    // The per-cycle counts for `ldcbf-sim deadline --instructions FILE`: the
    // first two passes (the third, people walking into a robot that does not
    // react, is reported on its own below).
    let csv_path = workspace_root().join("firmware/target/instructions.csv");
    let mut csv = format!("{INSTRUCTIONS_HEADER}\n");
    for c in run.cycles.iter().filter(|c| c.index < WALK_INTO_START) {
        writeln!(
            csv,
            "{},{},{},{}",
            c.index,
            c.status,
            c.iterations,
            instructions(c)
        )
        .unwrap();
    }
    std::fs::write(&csv_path, csv)
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", csv_path.display()));
    // The third pass's counts, in the same format (index within the pass),
    // for the fit of firmware/README.md ("where the instructions go").
    let walk_path = workspace_root().join("firmware/target/instructions-walk-into.csv");
    let mut walk_csv = format!("{INSTRUCTIONS_HEADER}\n");
    for c in run.cycles.iter().filter(|c| c.index >= WALK_INTO_START) {
        writeln!(
            walk_csv,
            "{},{},{},{}",
            c.index - WALK_INTO_START,
            c.status,
            c.iterations,
            instructions(c)
        )
        .unwrap();
    }
    std::fs::write(&walk_path, walk_csv)
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", walk_path.display()));
    let first_two = |c: &FirmwareCycle| c.index < WALK_INTO_START;
    let (n_all, med_all, max_all) = stats(&first_two);
    let (n_opt, med_opt, max_opt) = stats(&|c| first_two(c) && c.status == "optimal");
    let (n_fb, med_fb, max_fb) = stats(&|c| first_two(c) && c.status != "optimal");
    let (n_rest, med_rest, max_rest) = stats(&|c| c.index < RECORDED_CYCLES);
    let (n_mov, med_mov, max_mov) = stats(&|c| c.index >= RECORDED_CYCLES && first_two(c));
    let (n_walk, med_walk, max_walk) = stats(&|c| !first_two(c));
    let (n_wr, med_wr, max_wr) = stats(&|c| !first_two(c) && c.status != "optimal");
    let (n_wr_over, ..) = stats(&|c| !first_two(c) && instructions(c) > TARGET_INSTRUCTIONS);

    // Memory.
    let (text, data, bss, recorded_bytes) = elf_sizes(&elf, "8recorded6CYCLES");
    assert_eq!(
        recorded_bytes,
        (std::mem::size_of::<Row>() * recorded::CYCLES.len()) as u64,
        "size of the recorded::CYCLES symbol"
    );
    let cycle_stack = run.cycles.iter().map(|c| c.stack).max().unwrap_or(0);
    let flash = text + data - recorded_bytes;
    let ram_loop = data + bss + run.main_stack_depth + cycle_stack;
    let ram_startup = data + bss + run.startup_stack_peak;

    println!(
        "firmware vs host: {} cycles, commands agree to {worst:e} (tolerance \
         {COMMAND_TOL:e}), statuses equal; solver iterations differ in \
         {iteration_mismatches} cycles",
        host.len()
    );
    println!("determinism: two QEMU runs (-icount shift={ICOUNT_SHIFT}) printed identical output");
    println!(
        "wrote the instructions per cycle to {} (for `ldcbf-sim deadline --instructions`), \
         the third pass's to {}",
        csv_path.display(),
        walk_path.display()
    );
    println!(
        "instructions per cycle, first two passes: all {n_all}: median {med_all} max \
         {max_all}; optimal {n_opt}: median {med_opt} max {max_opt}; fallback {n_fb}: median \
         {med_fb} max {max_fb}"
    );
    println!(
        "instructions per cycle by pass: obstacles at rest {n_rest}: median {med_rest} max \
         {max_rest}; moving away {n_mov}: median {med_mov} max {max_mov}; walking into the \
         path {n_walk}: median {med_walk} max {max_walk} (its {n_wr} infeasible cycles: \
         median {med_wr} max {max_wr}; {n_wr_over} cycles above {TARGET_INSTRUCTIONS})"
    );
    println!(
        "ELF: text {text} data {data} bss {bss} (text includes the recorded cycles, \
         {recorded_bytes} bytes)"
    );
    println!(
        "stack: start-up peak {}, main's frame {}, a cycle's high-water mark {cycle_stack}",
        run.startup_stack_peak, run.main_stack_depth
    );
    let budgets = budgets(max_opt, max_all, max_walk, flash, ram_loop, ram_startup);
    println!(
        "{:<58} {:>9} {:>9} {:>9}",
        "budget", "value", "target", "ceiling"
    );
    for b in &budgets {
        println!(
            "{:<58} {:>9} {:>9} {:>9} {}",
            b.what,
            b.value,
            b.target,
            b.ceiling,
            if b.value <= b.target {
                "met"
            } else {
                "NOT met"
            }
        );
    }
    let over: Vec<_> = budgets.iter().filter(|b| b.value > b.ceiling).collect();
    assert!(over.is_empty(), "over the enforced ceiling: {over:?}");
}

/// A measured quantity, its target and the ceiling this test enforces.
#[derive(Debug)]
struct Budget {
    what: &'static str,
    value: u64,
    target: u64,
    ceiling: u64,
}

/// The enforced ceilings: the targets, but for the walk-into pass (a
/// ceiling just above today's value, so that a regression fails).
fn budgets(
    max_opt: u64,
    max_all: u64,
    max_walk: u64,
    flash: u64,
    ram_loop: u64,
    ram_startup: u64,
) -> [Budget; 6] {
    [
        Budget {
            what: "instructions, cycles with a solved QP (max)",
            value: max_opt,
            target: TARGET_INSTRUCTIONS,
            ceiling: TARGET_INSTRUCTIONS,
        },
        Budget {
            // Infeasible cycles run the priority scheme (controller/src/relax/):
            // the nominal solve and two or three probes (7 of the 15 recorded
            // ones take three). Met (max ~87k) since the firmware uses the
            // FPU's square root (feature `hw-sqrt`) and the probes solve the
            // selected rows in place (`solve_selected`) instead of copying them.
            what: "instructions, all cycles incl. infeasible (max)",
            value: max_all,
            target: TARGET_INSTRUCTIONS,
            ceiling: TARGET_INSTRUCTIONS,
        },
        Budget {
            // The third pass: people walking into the recorded path, most
            // cycles infeasible with a person in the conflict (confined
            // safety relaxation and give-way: the nominal solve and two to
            // four probes). Met (firmware/README.md): the scan of a row that
            // holds is its dot product and one integer compare.
            what: "instructions, people walking into the path (max)",
            value: max_walk,
            target: TARGET_INSTRUCTIONS,
            ceiling: WALK_INTO_CEILING,
        },
        Budget {
            // Met since the controller has no panicking branch left (nopanic/):
            // no panic message, so no float formatting, is linked. The firmware's
            // controller is `Controller::UNCONFIGURED` in a `static`: all zero
            // bytes, so `.bss`; were it not, its ~4.6 KiB would land in `.data`
            // (flash) and fail this budget.
            what: "flash bytes: text + data - recorded cycles",
            value: flash,
            target: TARGET_FLASH,
            ceiling: TARGET_FLASH,
        },
        Budget {
            what: "RAM bytes, control loop: data + bss + main + cycle stack",
            value: ram_loop,
            target: TARGET_RAM,
            ceiling: TARGET_RAM,
        },
        Budget {
            // Met since the firmware configures its `static` controller in place
            // (`Controller::configure`) instead of moving `Controller::new`'s
            // result (and its temporaries) through the stack.
            what: "RAM bytes, start-up: data + bss + start-up stack peak",
            value: ram_startup,
            target: TARGET_RAM,
            ceiling: TARGET_RAM,
        },
    ]
}
