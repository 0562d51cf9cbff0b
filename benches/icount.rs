//! Workloads for the deterministic instruction-count guard (`tools/icount.py`,
//! run by `.ci/run`; `docs/solvers.md`, "Instruction counts").
//!
//! `icount WORKLOAD LIPMWALK_DIR` prepares one workload's inputs, then runs its
//! measured part once inside [`counted`], the only function callgrind counts
//! (`valgrind --tool=callgrind --collect-atstart=no
//! --toggle-collect='*icount::counted*'`). Everything the measured part needs is
//! built before the call, and every input is fixed (files read in name order,
//! seeded random QPs, a recorded walk), so the same binary executes the same
//! instructions on any machine. `tools/icount.py` keeps only the instructions of
//! this binary (not of the C library, whose `memcpy` variant depends on the
//! CPU).
//!
//! Workloads (`icount list` prints them):
//!
//! * `lipmwalk_solve`: `DualActiveSet::solve` (static `(16, 32)`, cold start)
//!   on each of the 30 LIPMWALK QPs, everything done with the rows inside;
//! * `lipmwalk_ldp`: `LdpSolver::solve` on the same QPs, `prepare` and `load`
//!   outside (the LDP path of `qp solve`);
//! * `step_n3`, `step_n10`, `step_n20`: `Controller::step` (capacity 8, the
//!   `paper` obstacles, budgets for the horizon) over the cycles of a recorded
//!   walk of 40 steps toward the `paper` goal, one warm controller;
//! * `n50_solve`, `n50_ldp`: the `Dyn` solver and LDP path on 10 seeded random
//!   QPs with `n = 50`, `m = 100` (`ldcbf_reference::random_problem`).
//!
//! Run natively (`cargo bench --bench icount`) it checks that every workload
//! runs and prints how to count them.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use ldcbf_controller::nalgebra::{Const, DefaultAllocator, Dim, Dyn, Vector2};
use ldcbf_controller::qp::QpSettings;
use ldcbf_controller::{
    Config, Controller, CycleInput, DenseQpOf, DualActiveSetOf, LdpLoadedOf, LdpSolverOf,
    QpAllocator, constraint_capacity,
};
use ldcbf_nav::fixtures::{PAPER_GOAL, paper_obstacles, walk};
use ldcbf_reference::{DenseProblem, QpKind, random_problem};

/// Iteration budget of every solve (above every workload's need).
const MAX_ITER: u32 = 400;

/// The solver's settings: the defaults with [`MAX_ITER`].
const SETTINGS: QpSettings = QpSettings {
    tol_primal: 1e-10,
    tol_dependence: 1e-12,
    hot_start: true,
    max_iter: MAX_ITER,
};
/// Steps of the recorded walks.
const WALK_STEPS: usize = 40;
/// Seeds of the `n = 50` set.
const N50_SEEDS: std::ops::Range<u64> = 0..10;

/// The names of the workloads, in the order `tools/icount.py` reports them.
const WORKLOADS: [&str; 7] = [
    "lipmwalk_solve",
    "lipmwalk_ldp",
    "step_n3",
    "step_n10",
    "step_n20",
    "n50_solve",
    "n50_ldp",
];

/// A solver with the QP it solves.
type Solver<V, C> = (DualActiveSetOf<V, C>, DenseQpOf<V, C>);
/// An LDP path with its loaded `(q, h)`.
type Ldp<V, C> = (LdpSolverOf<V, C>, LdpLoadedOf<V, C>);

type Obstacles = Vec<ldcbf_controller::ConvexPolygon<8>>;

/// One prepared workload: its inputs, built outside the counted region.
enum Work<'a> {
    LipSolve(
        Vec<(
            DualActiveSetOf<Const<16>, Const<32>>,
            DenseQpOf<Const<16>, Const<32>>,
        )>,
    ),
    LipLdp(
        Vec<(
            LdpSolverOf<Const<16>, Const<32>>,
            LdpLoadedOf<Const<16>, Const<32>>,
        )>,
    ),
    Step3(
        Box<Controller<3, 6, { constraint_capacity(3, 8, false) }, 8>>,
        Vec<CycleInput<'a, 8>>,
    ),
    Step10(
        Box<Controller<10, 20, { constraint_capacity(10, 8, false) }, 8>>,
        Vec<CycleInput<'a, 8>>,
    ),
    Step20(
        Box<Controller<20, 40, { constraint_capacity(20, 8, false) }, 8>>,
        Vec<CycleInput<'a, 8>>,
    ),
    DynSolve(Vec<(DualActiveSetOf<Dyn, Dyn>, DenseQpOf<Dyn, Dyn>)>),
    DynLdp(Vec<(LdpSolverOf<Dyn, Dyn>, LdpLoadedOf<Dyn, Dyn>)>),
}

/// The measured part of a workload: the only function callgrind counts. Returns
/// a checksum (iterations and statuses) so that nothing is optimised away.
#[inline(never)]
fn counted(work: &mut Work<'_>) -> u64 {
    match work {
        Work::LipSolve(v) => solves(v),
        Work::LipLdp(v) => ldp_solves(v),
        Work::Step3(c, inputs) => steps(c, inputs),
        Work::Step10(c, inputs) => steps(c, inputs),
        Work::Step20(c, inputs) => steps(c, inputs),
        Work::DynSolve(v) => solves(v),
        Work::DynLdp(v) => ldp_solves(v),
    }
}

/// `solve` (cold) on each QP; the sum of the iterations.
#[inline(always)]
fn solves<V: Dim, C: Dim>(v: &[Solver<V, C>]) -> u64
where
    DefaultAllocator: QpAllocator<V, C>,
{
    v.iter()
        .map(|(s, qp)| u64::from(s.solve(black_box(qp), &[]).iterations))
        .sum()
}

/// The LDP `solve` (cold) on each loaded QP; the sum of the iterations.
#[inline(always)]
fn ldp_solves<V: Dim, C: Dim>(v: &[Ldp<V, C>]) -> u64
where
    DefaultAllocator: QpAllocator<V, C>,
{
    v.iter()
        .map(|(s, l)| u64::from(s.solve(black_box(l), &[]).iterations))
        .sum()
}

/// Runs `step` over `inputs` in order; the sum of the solver iterations.
fn steps<const N: usize, const NV: usize, const NC: usize>(
    ctl: &mut Controller<N, NV, NC, 8>,
    inputs: &[CycleInput<'_, 8>],
) -> u64 {
    inputs
        .iter()
        .map(|c| u64::from(ctl.step(black_box(c), None).info.iterations))
        .sum()
}

/// The LIPMWALK QPs of `dir` (`*.npz`, in name order).
fn lipmwalk(dir: &Path) -> Vec<DenseProblem> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "npz"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{}: no .npz files", dir.display());
    files
        .iter()
        .map(|f| DenseProblem::from_npz(f).unwrap_or_else(|e| panic!("{}: {e}", f.display())))
        .collect()
}

/// The cycle inputs of a recorded walk with horizon `N`, and a fresh
/// controller of the same sizes.
fn walk_inputs<const N: usize, const NV: usize, const NC: usize>(
    obs: &Obstacles,
) -> (Box<Controller<N, NV, NC, 8>>, Vec<CycleInput<'_, 8>>) {
    let cycles = walk::<N, NV, NC, 8, 8>(obs, Vector2::from(PAPER_GOAL), WALK_STEPS);
    let inputs = cycles.iter().map(|(c, _)| c.input(obs)).collect();
    let config = Config::default().with_budgets_for_horizon(N);
    let ctl = Controller::<N, NV, NC, 8>::new(config).expect("valid configuration");
    (Box::new(ctl), inputs)
}

/// The `n = 50` set as sized QPs with their solvers.
fn n50() -> Vec<(DualActiveSetOf<Dyn, Dyn>, DenseQpOf<Dyn, Dyn>)> {
    N50_SEEDS
        .map(|seed| {
            let p = random_problem(seed, 50, 100, 0, false, QpKind::Feasible);
            let (h, qp) = p.to_qp(Dyn(p.n), Dyn(p.rows())).expect("sized QP");
            let s = DualActiveSetOf::new(&h, SETTINGS).expect("definite P");
            (s, qp)
        })
        .collect()
}

/// The LDP path of each QP, prepared and loaded.
fn ldp_of<V: Dim, C: Dim>(v: &[Solver<V, C>]) -> Vec<Ldp<V, C>>
where
    DefaultAllocator: QpAllocator<V, C>,
{
    v.iter()
        .map(|(s, qp)| {
            let l = LdpSolverOf::prepare(s, qp);
            let loaded = l.load(&qp.q, &qp.h);
            (l, loaded)
        })
        .collect()
}

fn prepare<'a>(name: &str, dir: &Path, obs: &'a Obstacles) -> Work<'a> {
    let lip = || {
        lipmwalk(dir)
            .iter()
            .map(|p| {
                let (h, qp) = p
                    .to_qp(Const::<16>, Const::<32>)
                    .expect("LIPMWALK is (16, 32)");
                let s = DualActiveSetOf::new(&h, SETTINGS).expect("definite P");
                (s, qp)
            })
            .collect::<Vec<_>>()
    };
    match name {
        "lipmwalk_solve" => Work::LipSolve(lip()),
        "lipmwalk_ldp" => Work::LipLdp(ldp_of(&lip())),
        "step_n3" => {
            let (c, i) = walk_inputs::<3, 6, { constraint_capacity(3, 8, false) }>(obs);
            Work::Step3(c, i)
        }
        "step_n10" => {
            let (c, i) = walk_inputs::<10, 20, { constraint_capacity(10, 8, false) }>(obs);
            Work::Step10(c, i)
        }
        "step_n20" => {
            let (c, i) = walk_inputs::<20, 40, { constraint_capacity(20, 8, false) }>(obs);
            Work::Step20(c, i)
        }
        "n50_solve" => Work::DynSolve(n50()),
        "n50_ldp" => Work::DynLdp(ldp_of(&n50())),
        other => {
            eprintln!(
                "icount: unknown workload `{other}` (known: {})",
                WORKLOADS.join(", ")
            );
            std::process::exit(2);
        }
    }
}

fn main() {
    // `cargo bench` passes `--bench`; skip flags.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    match args.as_slice() {
        [w] if w == "list" => println!("{}", WORKLOADS.join("\n")),
        [w, dir] => {
            let obs = paper_obstacles::<8>();
            let mut work = prepare(w, Path::new(dir), &obs);
            println!("{w}: checksum {}", counted(&mut work));
        }
        _ => {
            // Natively: run every workload once on the repository's data.
            let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/lipmwalk");
            let obs = paper_obstacles::<8>();
            for w in WORKLOADS {
                let mut work = prepare(w, &dir, &obs);
                println!("{w}: checksum {}", counted(&mut work));
            }
            println!("count them with `python3 tools/icount.py` (valgrind's callgrind)");
        }
    }
}
