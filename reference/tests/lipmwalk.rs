//! The 30 external LIP-walking QPs of `tests/data/lipmwalk/` (n = 16,
//! m = 32, from the public mpc_qpbenchmark set), solved by our dual active-set
//! solver at that fixed size and by Clarabel: the docs/maths.md §3 contract
//! (primal 1e-6 scaled, objective 1e-8 relative, feasibility) must hold for all.
//! The same for the least-distance path (`LdpSolver`, prepared once for the
//! shared `P` and `G`, loaded per file), which must also match `solve`.

use std::path::PathBuf;

use ldcbf_controller::{DualActiveSet, LdpSolver, QpSettings};
use ldcbf_reference::{DenseProblem, compare, kkt, solve_clarabel, solve_own};

/// `tests/data/lipmwalk` of the repository (source and license in its README).
fn data_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/lipmwalk");
    assert!(
        dir.is_dir(),
        "test data missing: expected the external QP set at {}",
        dir.display()
    );
    dir
}

#[test]
fn lipmwalk_agrees_with_clarabel() {
    let dir = data_dir();
    let mut worst_primal: f64 = 0.0;
    let mut worst_obj: f64 = 0.0;
    let mut worst_kkt: f64 = 0.0;
    let mut max_iter = 0;
    for i in 0..30 {
        let path = dir.join(format!("LIPMWALK{i}.npz"));
        let p = DenseProblem::from_npz(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((p.n, p.m), (16, 32), "{}", path.display());
        let own = solve_own::<16, 32>(&p, 200).unwrap();
        let r = solve_clarabel(&p);
        let a = compare(&p, &own, &r);
        assert!(
            a.holds(),
            "{}: {a:?} (ours {:?}, Clarabel {:?})",
            path.display(),
            own.status,
            r.raw_status
        );
        assert!(a.both_solved, "{}: expected a feasible QP", path.display());
        let k = kkt(&p, own.x.as_slice(), &own.lambda.as_slice()[..p.m]);
        worst_primal = worst_primal.max(a.primal);
        worst_obj = worst_obj.max(a.objective);
        worst_kkt = worst_kkt.max(k.max());
        max_iter = max_iter.max(own.iterations);
    }
    println!(
        "LIPMWALK: worst scaled primal difference {worst_primal:.3e}, worst relative objective \
         difference {worst_obj:.3e}, worst KKT residual {worst_kkt:.3e}, max iterations {max_iter}"
    );
    assert!(worst_kkt <= 1e-8, "KKT residual {worst_kkt:e}");
}

#[test]
fn lipmwalk_ldp_path_agrees_with_clarabel_and_solve() {
    let dir = data_dir();
    let first =
        DenseProblem::from_npz(&dir.join("LIPMWALK0.npz")).unwrap_or_else(|e| panic!("{e}"));
    let (h0, qp0) = first.to_fixed::<16, 32>().unwrap();
    let solver = DualActiveSet::<16, 32>::new(&h0, QpSettings::default()).unwrap();
    // P and G are the same in all 30 files: one preparation serves all.
    let ldp = LdpSolver::prepare(&solver, &qp0);
    let (mut worst_primal, mut worst_kkt, mut worst_vs_solve): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for i in 0..30 {
        let path = dir.join(format!("LIPMWALK{i}.npz"));
        let p = DenseProblem::from_npz(&path).unwrap_or_else(|e| panic!("{e}"));
        let (h, qp) = p.to_fixed::<16, 32>().unwrap();
        assert_eq!(h, h0, "{}: P differs from LIPMWALK0", path.display());
        assert_eq!(
            qp.gt,
            qp0.gt,
            "{}: G differs from LIPMWALK0",
            path.display()
        );
        let own = ldp.solve(&ldp.load(&qp.q, &qp.h), &[false; 32]);
        let r = solve_clarabel(&p);
        let a = compare(&p, &own, &r);
        assert!(a.holds() && a.both_solved, "{}: {a:?}", path.display());
        let k = kkt(&p, own.x.as_slice(), &own.lambda.as_slice()[..p.m]);
        let gi = solver.solve(&qp, &[false; 32]);
        assert_eq!(gi.iterations, own.iterations, "{}", path.display());
        let d = (gi.x - own.x).amax() / gi.x.amax().max(1.0);
        worst_vs_solve = worst_vs_solve.max(d);
        worst_primal = worst_primal.max(a.primal);
        worst_kkt = worst_kkt.max(k.max());
    }
    println!(
        "LIPMWALK, LDP path: worst scaled primal difference to Clarabel {worst_primal:.3e}, to \
         solve {worst_vs_solve:.3e}, worst KKT residual {worst_kkt:.3e}"
    );
    assert!(worst_kkt <= 1e-8, "KKT residual {worst_kkt:e}");
    assert!(
        worst_vs_solve <= 1e-9,
        "x differs from solve by {worst_vs_solve:e}"
    );
}
