//! Random QPs of every member kind ([`random_problem`]) solved by Clarabel: the
//! feasible ones solved with small KKT residuals, the infeasible ones reported
//! infeasible with a valid Farkas certificate; and our fixed-size solver on the
//! ones without equality rows, agreeing with Clarabel row by row.

use ldcbf_controller::QpStatus;
use ldcbf_reference::{
    Candidate, DenseProblem, QpKind, RefStatus, compare_stacked, farkas_holds, farkas_residuals,
    kkt_stacked, random_problem, solve_clarabel, solve_own,
};

/// `(n, m, me)` of the sizes tested: `m` up to `4n`, `me` up to `n/2`.
const SIZES: [(usize, usize, usize); 5] = [
    (2, 8, 1),
    (8, 32, 4),
    (30, 60, 15),
    (50, 100, 25),
    (100, 400, 50),
];

/// Largest `|v|`.
fn amax(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a, x| a.max(x.abs()))
}

#[test]
fn the_generator_is_deterministic_and_well_conditioned() {
    let a = random_problem(7, 8, 32, 4, true, QpKind::Feasible);
    assert_eq!(a, random_problem(7, 8, 32, 4, true, QpKind::Feasible));
    assert_ne!(a, random_problem(8, 8, 32, 4, true, QpKind::Feasible));
    a.validate().unwrap();
    assert_eq!((a.n, a.m, a.me, a.lb.len(), a.ub.len()), (8, 32, 4, 8, 8));
    let p = nalgebra::DMatrix::from_row_slice(a.n, a.n, &a.P);
    assert_eq!(p, p.transpose());
    let eig = p.symmetric_eigenvalues();
    let cond = eig.max() / eig.min();
    assert!(eig.min() > 0.0 && cond < 1.01e4, "cond {cond:e}");
    // Sizes a kind needs are raised.
    let b = random_problem(1, 3, 0, 0, false, QpKind::OpposedRows);
    assert_eq!(b.m, 2);
    let c = random_problem(1, 3, 0, 0, false, QpKind::EqualityVsBounds);
    assert_eq!((c.me, c.lb.len(), c.ub.len()), (1, 3, 3));
    let d = random_problem(1, 0, 0, 0, false, QpKind::EqualityVsRows);
    assert_eq!((d.n, d.m, d.me), (1, 1, 1));
    for p in [b, c, d] {
        p.validate().unwrap();
    }
}

/// Every kind at every size: `(problem, kind)`, two seeds each for the feasible
/// kind (with and without bounds).
fn instances() -> Vec<(DenseProblem, QpKind)> {
    let mut out = Vec::new();
    for (s, &(n, m, me)) in SIZES.iter().enumerate() {
        let seed = 100 * s as u64;
        for (k, (kind, me, bounds)) in [
            (QpKind::Feasible, me, true),
            (QpKind::Feasible, 0, false),
            (QpKind::OpposedRows, me, true),
            (QpKind::EqualityVsBounds, me, true),
            (QpKind::EqualityVsRows, me, false),
        ]
        .into_iter()
        .enumerate()
        {
            out.push((
                random_problem(seed + k as u64, n, m, me, bounds, kind),
                kind,
            ));
        }
    }
    out
}

#[test]
fn clarabel_solves_the_feasible_and_certifies_the_infeasible() {
    let mut worst_kkt: f64 = 0.0;
    for (p, kind) in instances() {
        let tag = format!("n = {}, m = {}, me = {}, {kind:?}", p.n, p.m, p.me);
        let r = solve_clarabel(&p);
        assert_eq!(r.z.len(), p.rows(), "{tag}");
        if kind.is_feasible() {
            assert_eq!(r.status, RefStatus::Solved, "{tag}: {:?}", r.raw_status);
            let k = kkt_stacked(&p, &r.x, &r.z).unwrap();
            let scale = amax(&p.q).max(1.0);
            assert!(k.max() <= 1e-9 * scale, "{tag}: {k:?}");
            worst_kkt = worst_kkt.max(k.max() / scale);
            // The multipliers map back member by member.
            let y = p.stacked().split_multipliers(&r.z).unwrap();
            assert_eq!((y.eq.len(), y.ineq.len(), y.lower.len()), (p.me, p.m, p.n));
        } else {
            assert_eq!(r.status, RefStatus::Infeasible, "{tag}: {:?}", r.raw_status);
            let st = p.stacked();
            assert!(
                farkas_holds(&st, &r.z, 1e-9),
                "{tag}: {:?}",
                farkas_residuals(&st, &r.z)
            );
        }
    }
    println!("worst scaled KKT residual of Clarabel's solutions: {worst_kkt:.2e}");
}

/// Our solver at the fixed size `(NV, NC)` on `p` (no equality rows), checked
/// against Clarabel with [`compare_stacked`].
fn own_agrees<const NV: usize, const NC: usize>(p: &DenseProblem, tag: &str) {
    let own = solve_own::<NV, NC>(p, 500).unwrap();
    let r = solve_clarabel(p);
    let y = &own.lambda.as_slice()[..p.rows()];
    let c = Candidate {
        status: own.status,
        x: own.x.as_slice(),
        y,
        objective: own.objective,
    };
    let a = compare_stacked(p, &c, &r);
    assert!(
        a.holds(),
        "{tag}: {a:?} (ours {:?}, Clarabel {:?})",
        own.status,
        r.raw_status
    );
    if own.status == QpStatus::Solved {
        let k = kkt_stacked(p, own.x.as_slice(), y).unwrap();
        assert!(k.max() <= 1e-9 * amax(&p.q).max(1.0), "{tag}: {k:?}");
    }
}

#[test]
fn our_solver_agrees_on_random_problems_without_equalities() {
    for seed in 0..4 {
        for kind in [QpKind::Feasible, QpKind::OpposedRows] {
            let tag = format!("seed {seed}, {kind:?}");
            // Rows: m + up to 2n bounds.
            own_agrees::<2, 16>(&random_problem(seed, 2, 8, 0, true, kind), &tag);
            own_agrees::<8, 48>(&random_problem(seed, 8, 32, 0, true, kind), &tag);
            own_agrees::<16, 96>(&random_problem(seed, 16, 64, 0, seed % 2 == 0, kind), &tag);
        }
    }
}
