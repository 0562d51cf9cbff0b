//! The non-condensed LIP MPC QPs of `tests/data/lipmpc` (positive
//! semidefinite `P`, dynamics as equality rows, bounds on every variable):
//! our run-time-sized solver (proximal-point iterations) and its static
//! instance agree with Clarabel on every file, bit for bit with each other.

use std::path::PathBuf;

use ldcbf_controller::QpStatus;
use ldcbf_reference::{Candidate, DenseProblem, compare_stacked, solve_clarabel, solve_own_dyn};

fn files() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/lipmpc");
    let mut out: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "npz"))
        .collect();
    out.sort();
    out
}

#[test]
fn semidefinite_mpc_qps_agree_with_clarabel() {
    let files = files();
    assert_eq!(files.len(), 6, "tests/data/lipmpc holds 6 files");
    for f in &files {
        let p = DenseProblem::from_npz(f).unwrap_or_else(|e| panic!("{e}"));
        assert!(p.me > 0 && !p.lb.is_empty(), "{}", f.display());
        let own = solve_own_dyn(&p, 1000).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(own.status, QpStatus::Solved, "{}", f.display());
        let r = solve_clarabel(&p);
        let c = Candidate {
            status: own.status,
            x: own.x.as_slice(),
            y: own.lambda.as_slice(),
            objective: own.objective,
        };
        let a = compare_stacked(&p, &c, &r);
        assert!(a.holds(), "{}: {a:?}", f.display());
        // The static instance (n = 48, the stacked rows) runs the same code.
        let fixed = ldcbf_reference::solve_own::<48, 160>(&p, 1000).unwrap();
        assert_eq!(fixed.iterations, own.iterations, "{}", f.display());
        assert!(
            fixed
                .x
                .iter()
                .zip(own.x.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "{}",
            f.display()
        );
    }
}
