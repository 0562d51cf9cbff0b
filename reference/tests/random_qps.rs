//! Random QPs of every member kind ([`random_problem`]) solved by Clarabel: the
//! feasible ones solved with small KKT residuals, the infeasible ones reported
//! infeasible with a valid Farkas certificate; our run-time-sized solver on
//! all of them (equalities, bounds, infeasible ones included) and our
//! fixed-size solver on the ones without equality rows, agreeing with
//! Clarabel row by row; and the two instances bit for bit equal.

use ldcbf_controller::QpStatus;
use ldcbf_reference::{
    Candidate, DenseProblem, QpKind, RefStatus, compare_stacked, farkas_holds, farkas_residuals,
    kkt_stacked, random_problem, solve_clarabel, solve_own, solve_own_dyn,
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

/// `own` (status, `x`, stacked multipliers or certificate, objective) checked
/// against Clarabel with [`compare_stacked`], and its KKT residuals when
/// solved. Returns the scaled primal and the objective difference (0 unless
/// both solved).
fn agrees(
    p: &DenseProblem,
    status: QpStatus,
    x: &[f64],
    y: &[f64],
    objective: f64,
    tag: &str,
) -> (f64, f64) {
    let r = solve_clarabel(p);
    let c = Candidate {
        status,
        x,
        y,
        objective,
    };
    let a = compare_stacked(p, &c, &r);
    assert!(
        a.holds(),
        "{tag}: {a:?} (ours {status:?}, Clarabel {:?})",
        r.raw_status
    );
    if status == QpStatus::Solved {
        let k = kkt_stacked(p, x, y).unwrap();
        assert!(k.max() <= 1e-9 * amax(&p.q).max(1.0), "{tag}: {k:?}");
        (a.dx / a.x_ref_norm.max(1.0), a.objective)
    } else {
        (0.0, 0.0)
    }
}

#[test]
fn the_dynamic_solver_agrees_at_every_size_with_equalities_bounds_and_infeasible_ones() {
    let mut worst: f64 = 0.0;
    // Per n: (solved, infeasible, worst scaled primal difference, worst
    // objective difference).
    let mut by_n = std::collections::BTreeMap::<usize, (u32, u32, f64, f64)>::new();
    let (mut solved, mut infeasible) = (0, 0);
    for (i, (p, kind)) in instances().into_iter().enumerate() {
        // And a second seed of each, for more active sets.
        let q = random_problem(1000 + i as u64, p.n, p.m, p.me, !p.lb.is_empty(), kind);
        for p in [p, q] {
            let tag = format!("n = {}, m = {}, me = {}, {kind:?}", p.n, p.m, p.me);
            let own = solve_own_dyn(&p, 10_000).unwrap();
            assert_eq!(own.lambda.len(), p.rows(), "{tag}");
            assert_eq!(
                own.status == QpStatus::Solved,
                kind.is_feasible(),
                "{tag}: {:?}",
                own.status
            );
            match own.status {
                QpStatus::Solved => solved += 1,
                QpStatus::Infeasible => infeasible += 1,
                s => panic!("{tag}: {s:?}"),
            }
            let (d, dobj) = agrees(
                &p,
                own.status,
                own.x.as_slice(),
                own.lambda.as_slice(),
                own.objective,
                &tag,
            );
            worst = worst.max(d);
            let e = by_n.entry(p.n).or_default();
            match own.status {
                QpStatus::Solved => e.0 += 1,
                _ => e.1 += 1,
            }
            e.2 = e.2.max(d);
            e.3 = e.3.max(dobj);
        }
    }
    assert_eq!((solved, infeasible), (20, 30));
    println!("worst scaled primal difference to Clarabel: {worst:.2e}");
    println!(
        "| n | solved | infeasible (certificate checked) | worst primal diff | worst objective diff |"
    );
    for (n, (s, i, dx, dobj)) in by_n {
        println!("| {n} | {s} | {i} | {dx:.1e} | {dobj:.1e} |");
    }
}

/// The static instance at `(NV, NC)` and the dynamic one on the same data:
/// the same status, iterations, active set and bits of `x`, multipliers and
/// objective.
fn static_and_dynamic_are_identical<const NV: usize, const NC: usize>(p: &DenseProblem) {
    let s = solve_own::<NV, NC>(p, 500).unwrap();
    let d = solve_own_dyn(p, 500).unwrap();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(s.status, d.status);
    assert_eq!(s.iterations, d.iterations);
    assert_eq!(s.active_set(), d.active_set());
    assert_eq!(bits(s.x.as_slice()), bits(d.x.as_slice()));
    assert_eq!(
        bits(&s.lambda.as_slice()[..p.rows()]),
        bits(d.lambda.as_slice())
    );
    assert_eq!(s.objective.to_bits(), d.objective.to_bits());
}

#[test]
fn static_and_dynamic_instances_are_bit_identical_on_the_controllers_sizes() {
    // The controller's sizes (N = 3: NV = 6; N = 5: 10; N = 8: 16; N = 10:
    // 20) and LIPMWALK's, feasible and infeasible, with and without bounds;
    // NV >= 16 also with equality rows (compiled in from there on).
    for seed in 0..6 {
        for kind in [QpKind::Feasible, QpKind::OpposedRows] {
            let b = seed % 2 == 0;
            static_and_dynamic_are_identical::<6, 48>(&random_problem(seed, 6, 30, 0, b, kind));
            static_and_dynamic_are_identical::<10, 80>(&random_problem(seed, 10, 50, 0, b, kind));
            static_and_dynamic_are_identical::<16, 128>(&random_problem(seed, 16, 80, 4, b, kind));
            static_and_dynamic_are_identical::<20, 160>(&random_problem(seed, 20, 100, 5, b, kind));
        }
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/lipmwalk");
    let mut files = 0;
    for f in std::fs::read_dir(&dir).unwrap() {
        let f = f.unwrap().path();
        if f.extension().is_none_or(|e| e != "npz") {
            continue;
        }
        let p = DenseProblem::from_npz(&f).unwrap();
        static_and_dynamic_are_identical::<16, 32>(&p);
        files += 1;
    }
    assert_eq!(files, 30);
}

#[test]
fn the_least_distance_path_agrees_with_the_orthogonal_one_with_equalities() {
    use ldcbf_controller::{DualActiveSetDyn, LdpSolverDyn, QpSettings};
    let mut checked = 0;
    for (i, (p, kind)) in instances().into_iter().enumerate() {
        let tag = format!("n = {}, m = {}, me = {}, {kind:?}", p.n, p.m, p.me);
        let (hess, qp) = p.to_dyn().unwrap();
        let settings = QpSettings {
            max_iter: 10_000,
            ..QpSettings::default()
        };
        let s = DualActiveSetDyn::new(&hess, settings).unwrap();
        let a = s.without_hot_start().solve(&qp, &[]);
        let ldp = LdpSolverDyn::prepare(&s, &qp);
        let b = ldp.solve_qp(&qp, &[]);
        assert_eq!(a.status, b.status, "{tag}");
        if a.status == QpStatus::Solved {
            let dx = (&a.x - &b.x).amax() / a.x.amax().max(1.0);
            assert!(dx <= 1e-9, "{tag}: {dx:e}");
            let y = b.lambda.as_slice();
            let k = kkt_stacked(&p, b.x.as_slice(), y).unwrap();
            assert!(k.max() <= 1e-9 * amax(&p.q).max(1.0), "{tag}: {k:?}");
        } else {
            assert!(
                farkas_holds(&p.stacked(), b.lambda.as_slice(), 1e-9),
                "{tag} ({i})"
            );
        }
        checked += 1;
    }
    assert_eq!(checked, 25);
}
