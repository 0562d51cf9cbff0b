//! Unit tests of the least-distance path: against `DualActiveSet::solve`.

use super::gram::chol_drop;
use super::*;
use crate::linalg::dot;

use crate::qp::QpSettings;
use crate::qp::{DenseQp, DualActiveSet, QpSolution};
use nalgebra::SVector;
use nalgebra::{Matrix2, SMatrix, Vector2};

/// Deterministic uniform numbers in [-1, 1) (64-bit LCG).
struct Rnd(u64);
impl Rnd {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// Checks a Farkas certificate: y >= 0, |G'y| small, h'y < 0.
fn assert_certificate<const NV: usize, const NC: usize>(
    qp: &DenseQp<NV, NC>,
    y: &SVector<f64, NC>,
) {
    let mut gty = SVector::<f64, NV>::zeros();
    let (mut hty, mut scale) = (0.0, 0.0f64);
    for (i, (g, h)) in qp.rows().enumerate() {
        assert!(y[i] >= 0.0);
        gty += g * y[i];
        hty += h * y[i];
        scale = scale.max(y[i] * g.amax());
    }
    assert!(gty.amax() <= 1e-10 * (1.0 + scale), "G'y = {gty:?}");
    assert!(hty < 0.0, "h'y = {hty}");
}

/// `(|G'y| / sum_i y_i |g_i|, h'y)` of a certificate `y >= 0`.
fn certificate_residual<const NV: usize, const NC: usize>(
    qp: &DenseQp<NV, NC>,
    y: &SVector<f64, NC>,
) -> (f64, f64) {
    let mut gty = SVector::<f64, NV>::zeros();
    let (mut hty, mut scale) = (0.0, 0.0);
    for (i, (g, h)) in qp.rows().enumerate() {
        assert!(y[i] >= 0.0);
        gty += g * y[i];
        hty += h * y[i];
        scale += y[i] * g.norm();
    }
    (if scale > 0.0 { gty.norm() / scale } else { 0.0 }, hty)
}

/// KKT conditions of a solution (stationarity, feasibility,
/// complementarity, signs), independent of either solver.
fn assert_kkt<const NV: usize, const NC: usize>(
    s: &DualActiveSet<NV, NC>,
    qp: &DenseQp<NV, NC>,
    sol: &QpSolution<NV, NC>,
) {
    let mut stat = s.hessian() * sol.x + qp.q;
    let scale = 1.0 + sol.lambda.amax() + qp.q.amax();
    for (i, (g, h)) in qp.rows().enumerate() {
        let slack = h - g.dot(&sol.x);
        assert!(sol.lambda[i] >= 0.0);
        assert!(
            slack >= -1e-9 * g.norm().max(1.0),
            "row {i} violated by {slack}"
        );
        assert!(
            (sol.lambda[i] * slack).abs() < 1e-9 * scale,
            "complementarity"
        );
        stat += g * sol.lambda[i];
    }
    assert!(stat.amax() < 1e-9 * scale, "stationarity {stat:?}");
}

/// The LDP path and `solve` on one QP: same status and iterations;
/// solved: x, objective and multipliers agree and satisfy KKT;
/// infeasible: both certificates are valid.
fn assert_same<const NV: usize, const NC: usize>(
    s: &DualActiveSet<NV, NC>,
    qp: &DenseQp<NV, NC>,
    prefer: &[bool; NC],
) -> QpStatus {
    let a = s.without_hot_start().solve(qp, prefer);
    let ldp = LdpSolver::prepare(s, qp);
    let b = ldp.solve_qp(qp, prefer);
    assert_eq!(a.status, b.status, "{qp:?}");
    assert_eq!(a.iterations, b.iterations);
    match b.status {
        QpStatus::Solved => {
            assert_kkt(s, qp, &b);
            let xs = a.x.amax().max(1.0);
            assert!((a.x - b.x).amax() <= 1e-9 * xs, "{} vs {}", a.x, b.x);
            let os = a.objective.abs().max(1.0);
            assert!((a.objective - b.objective).abs() <= 1e-9 * os);
            let ls = a.lambda.amax().max(1.0);
            assert!((a.lambda - b.lambda).amax() <= 1e-8 * ls);
            assert_eq!(a.active_set(), b.active_set());
        }
        QpStatus::Infeasible => {
            assert_certificate(qp, &a.lambda);
            assert_certificate(qp, &b.lambda);
        }
        other => panic!("unexpected status {other:?}"),
    }
    b.status
}

fn random_hessian<const NV: usize>(rnd: &mut Rnd, diagonal: bool) -> SMatrix<f64, NV, NV> {
    if diagonal {
        SMatrix::from_diagonal(&SVector::from_fn(|_, _| 0.1 + 10.0 * rnd.next().abs()))
    } else {
        let A = SMatrix::<f64, NV, NV>::from_fn(|_, _| rnd.next());
        A.transpose() * A + SMatrix::identity() * 0.1
    }
}

fn random_family<const NV: usize, const NC: usize>(seed: u64, count: usize) {
    let mut rnd = Rnd(seed);
    let (mut solved, mut infeasible) = (0, 0);
    for k in 0..count {
        let H = random_hessian::<NV>(&mut rnd, k % 2 == 0);
        let s = DualActiveSet::<NV, NC>::new(&H, QpSettings::default()).unwrap();
        let mut qp = DenseQp::<NV, NC>::with_q(SVector::from_fn(|_, _| 5.0 * rnd.next()));
        for _ in 0..(4 + k % (NC - 3)) {
            let g = SVector::<f64, NV>::from_fn(|_, _| rnd.next());
            qp.push_row(&g, rnd.next() + 0.3).unwrap();
        }
        let mut prefer = [false; NC];
        if k % 3 == 0 {
            for p in prefer.iter_mut().take(qp.m) {
                *p = rnd.next() > 0.5;
            }
        }
        match assert_same(&s, &qp, &prefer) {
            QpStatus::Solved => solved += 1,
            _ => infeasible += 1,
        }
    }
    assert!(
        solved > count / 4 && infeasible > count / 40,
        "{solved} solved, {infeasible} infeasible"
    );
}

#[test]
fn agrees_with_solve_on_random_qps_n6() {
    random_family::<6, 24>(0x2545_f491_4f6c_dd1d, 600);
}

#[test]
fn agrees_with_solve_on_random_qps_n16() {
    random_family::<16, 40>(0x9e37_79b9_7f4a_7c15, 300);
}

#[test]
fn one_fixed_g_many_q_h() {
    // One preparation, many loads: every solve matches `solve`.
    let mut rnd = Rnd(7);
    let H = random_hessian::<6>(&mut rnd, false);
    let s = DualActiveSet::<6, 16>::new(&H, QpSettings::default()).unwrap();
    let mut qp = DenseQp::<6, 16>::default();
    for _ in 0..16 {
        let g = SVector::<f64, 6>::from_fn(|_, _| rnd.next());
        qp.push_row(&g, 0.0).unwrap();
    }
    let ldp = LdpSolver::prepare(&s, &qp);
    for _ in 0..200 {
        qp.q = SVector::from_fn(|_, _| 5.0 * rnd.next());
        qp.h = SVector::from_fn(|_, _| rnd.next() + 0.4);
        let a = s.solve(&qp, &[false; 16]);
        let b = ldp.solve(&ldp.load(&qp.q, &qp.h), &[false; 16]);
        assert_eq!(a.status, b.status);
        assert_eq!(a.iterations, b.iterations);
        assert!((a.x - b.x).amax() <= 1e-9 * a.x.amax().max(1.0));
    }
}

/// Random QPs built to be degenerate: duplicated, scaled, negated and
/// nearly parallel rows, zero rows, rows through one point, scales from
/// 1e-6 to 1e6. Every LDP result must be a valid solution or certificate
/// (or IterationLimit/NumericalError only where `solve` says the same), and
/// the status must match `solve`'s.
fn degenerate_family<const NV: usize, const NC: usize>(seed: u64, count: usize) -> usize {
    let mut rnd = Rnd(seed);
    let mut same_iters = 0;
    for k in 0..count {
        let H = random_hessian::<NV>(&mut rnd, k % 3 == 0);
        let s = DualActiveSet::<NV, NC>::new(&H, QpSettings::default()).unwrap();
        let mut qp = DenseQp::<NV, NC>::with_q(SVector::from_fn(|_, _| 5.0 * rnd.next()));
        let x0 = SVector::<f64, NV>::from_fn(|_, _| rnd.next()); // a common point
        while qp.m < NC {
            let kind = (rnd.next().abs() * 7.0) as u32;
            let last = qp.m.checked_sub(1).map(|i| qp.get_row(i).unwrap());
            let (g, h) = match (kind, last) {
                (0, Some((g, h))) => (g, h), // duplicate
                (1, Some((g, h))) => {
                    let c = 10f64.powf(3.0 * rnd.next());
                    (g * c, h * c) // scaled copy
                }
                (2, Some((g, h))) => (-g, -h + 0.5 * rnd.next()), // opposite
                (3, Some((g, h))) => {
                    let e = [1e-6, 1e-10, 1e-14][k % 3];
                    (g + SVector::from_fn(|_, _| e * rnd.next()), h) // nearly parallel
                }
                (4, _) => (SVector::zeros(), rnd.next() + 0.2), // zero row
                (5, _) => {
                    let g = SVector::<f64, NV>::from_fn(|_, _| rnd.next());
                    let h = g.dot(&x0);
                    (g, h) // through x0
                }
                _ => {
                    let c = 10f64.powf(6.0 * rnd.next());
                    let g = SVector::<f64, NV>::from_fn(|_, _| c * rnd.next());
                    (g, c * (rnd.next() + 0.3))
                }
            };
            qp.push_row(&g, h).unwrap();
        }
        let a = s.solve(&qp, &[false; NC]);
        let b = LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; NC]);
        assert_eq!(a.status, b.status, "case {k}");
        match b.status {
            QpStatus::Solved => {
                let xs = a.x.amax().max(1.0);
                assert!(
                    (a.x - b.x).amax() <= 1e-7 * xs,
                    "case {k}: {} vs {}",
                    a.x,
                    b.x
                );
            }
            QpStatus::Infeasible => {
                // With nearly parallel rows `solve`'s certificate can be
                // inexact too: ours must be as good (to a factor 100).
                let (ra, ha) = certificate_residual(&qp, &a.lambda);
                let (rb, hb) = certificate_residual(&qp, &b.lambda);
                assert!(rb <= (100.0 * ra).max(1e-10), "case {k}: {rb:e} vs {ra:e}");
                assert!(hb < 0.0 || ha >= 0.0, "case {k}: h'y = {hb}");
            }
            _ => {}
        }
        same_iters += usize::from(a.iterations == b.iterations);
    }
    same_iters
}

#[test]
fn degenerate_random_qps_match_solve() {
    let n6 = degenerate_family::<6, 24>(11, 400);
    let n16 = degenerate_family::<16, 40>(12, 200);
    // Rounding may change a tie between degenerate rows, so the paths may
    // differ now and then; nearly always they are the same.
    assert!(
        n6 >= 380 && n16 >= 190,
        "same iteration counts: {n6}/400, {n16}/200"
    );
}

fn solver2() -> DualActiveSet<2, 8> {
    DualActiveSet::new(&Matrix2::new(2.0, 0.0, 0.0, 2.0), QpSettings::default()).unwrap()
}

fn qp2(rows: &[([f64; 2], f64)]) -> DenseQp<2, 8> {
    let mut qp = DenseQp::<2, 8>::with_q(Vector2::new(-2.0, -4.0));
    for &(g, h) in rows {
        qp.push_row(&Vector2::from(g), h).unwrap();
    }
    qp
}

#[test]
fn degenerate_rows() {
    let s = solver2();
    let dense =
        DualActiveSet::<2, 8>::new(&Matrix2::new(3.0, 1.0, 1.0, 2.0), QpSettings::default())
            .unwrap();
    let cases: [&[([f64; 2], f64)]; 8] = [
        // zero rows: satisfied, and one with h slightly negative but within tol
        &[([0.0, 0.0], 1.0), ([1.0, 1.0], 1.0), ([0.0, 0.0], -1e-12)],
        // duplicate rows (the second is linearly dependent once the first is active)
        &[([1.0, 1.0], 1.0), ([1.0, 1.0], 1.0), ([2.0, 2.0], 2.0)],
        // nearly parallel rows
        &[
            ([1.0, 1.0], 1.0),
            ([1.0, 1.0 + 1e-13], 1.0),
            ([1.0, 1.0 - 1e-9], 1.0),
        ],
        // three rows through the optimal vertex (degenerate vertex)
        &[
            ([1.0, 0.0], 0.0),
            ([0.0, 1.0], 0.0),
            ([1.0, 1.0], 0.0),
            ([1.0, 2.0], 0.0),
        ],
        // a drop is needed
        &[([1.0, 1.0], -2.0), ([0.0, 1.0], 0.0), ([1.0, 0.0], -1.0)],
        // infeasible: opposite half-planes, and parallel duplicates of them
        &[([1.0, 0.0], -1.0), ([-1.0, 0.0], -1.0), ([1.0, 0.0], -1.0)],
        // infeasible through a zero row with a negative right-hand side
        &[([1.0, 1.0], 1.0), ([0.0, 0.0], -1.0)],
        // infeasible triangle, one irrelevant row
        &[
            ([0.0, 1.0], 5.0),
            ([1.0, 1.0], -1.0),
            ([-1.0, 0.0], 0.0),
            ([0.0, -1.0], 0.0),
        ],
    ];
    for s in [&s, &dense] {
        for rows in cases {
            let qp = qp2(rows);
            assert_same(s, &qp, &[false; 8]);
            assert_same(s, &qp, &[true; 8]);
        }
    }
    let st: [QpStatus; 3] = [5, 6, 7].map(|k| assert_same(&solver2(), &qp2(cases[k]), &[false; 8]));
    assert!(st.iter().all(|s| s.is_infeasible()));
    // The zero-row certificate is e_1.
    let qp = qp2(cases[6]);
    let sol = LdpSolver::prepare(&solver2(), &qp).solve_qp(&qp, &[false; 8]);
    assert_eq!(sol.lambda[1], 1.0);
}

#[test]
fn ill_conditioned_active_set_falls_back_to_solve() {
    // min |x - c|^2 with c = (1e6, 0.05) inside the thin cone of the
    // normals of x <= 0 and x + 1e-7 y <= 0: both are active at (0, 0).
    // The row added second has a component of 1e-7 < PIVOT_FALLBACK
    // outside the first, so the result is `solve_prepared`'s, bit for bit.
    let s = solver2();
    let mut qp = qp2(&[([1.0, 0.0], 0.0), ([1.0, 1e-7], 0.0)]);
    qp.q = Vector2::new(-2e6, -0.1);
    let a = s.solve(&qp, &[false; 8]);
    let b = LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8]);
    assert_eq!(a.status, QpStatus::Solved);
    assert_eq!((a.status, a.iterations), (b.status, b.iterations));
    assert_eq!(a.x, b.x);
    assert_eq!(a.lambda, b.lambda);
    assert_eq!(a.n_active, 2);
}

#[test]
fn unconstrained_and_budget() {
    let s = solver2();
    let qp = qp2(&[]);
    let sol = LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8]);
    assert_eq!(sol.status, QpStatus::Solved);
    assert_eq!(sol.iterations, 0);
    assert!((sol.x - Vector2::new(1.0, 2.0)).amax() < 1e-14);
    assert!((sol.objective + 5.0).abs() < 1e-14);
    let qp = qp2(&[([1.0, 1.0], -2.0), ([0.0, 1.0], -1.0)]);
    let ldp = LdpSolver::prepare(&s, &qp);
    let full = ldp.solve_qp(&qp, &[false; 8]);
    assert_eq!((full.status, full.iterations), (QpStatus::Solved, 2));
    for budget in [0, 1] {
        let s = s.with_max_iter(budget);
        let a = s.solve(&qp, &[false; 8]);
        let b = LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8]);
        assert_eq!(b.status, QpStatus::IterationLimit);
        assert_eq!(b.iterations, budget);
        // The last iterate is the one of `solve`.
        assert!((a.x - b.x).amax() < 1e-12, "{} vs {}", a.x, b.x);
    }
}

#[test]
fn bad_input_is_numerical_error() {
    let s = solver2();
    let good = qp2(&[([1.0, 1.0], 1.0)]);
    let ldp = LdpSolver::prepare(&s, &good);
    let err = |sol: QpSolution<2, 8>| assert_eq!(sol.status, QpStatus::NumericalError);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        // q, h
        err(ldp.solve(&ldp.load(&Vector2::new(bad, 0.0), &good.h), &[false; 8]));
        let mut h = good.h;
        h[0] = bad;
        err(ldp.solve(&ldp.load(&good.q, &h), &[false; 8]));
        // G
        let qp = qp2(&[([1.0, bad], 1.0)]);
        err(LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8]));
    }
    // A row whose squared norm overflows.
    let qp = qp2(&[([1e200, 0.0], 1.0)]);
    err(LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[false; 8]));
    // Loaded data of a solver with another row count.
    let other = LdpSolver::prepare(&s, &qp2(&[([1.0, 0.0], 0.0), ([0.0, 1.0], 0.0)]));
    err(ldp.solve(&other.load(&good.q, &good.h), &[false; 8]));
    // The placeholder solver (H = 0): defined status, no panic.
    let ph = DualActiveSet::<2, 8>::PLACEHOLDER;
    let sol = LdpSolver::prepare(&ph, &good).solve_qp(&good, &[false; 8]);
    assert!(!sol.status.is_solved() || sol.x.iter().all(|v| v.is_finite()));
}

#[test]
fn chol_drop_keeps_the_gram_matrix() {
    // Rows of a random 5 x 5 lower-triangular factor; drop each row in turn.
    let mut rnd = Rnd(3);
    for l in 0..5 {
        let mut C = [[0.0f64; 5]; 5];
        for (i, row) in C.iter_mut().enumerate() {
            for (j, c) in row.iter_mut().enumerate().take(i + 1) {
                *c = if i == j {
                    1.0 + rnd.next().abs()
                } else {
                    rnd.next()
                };
            }
        }
        let gram = |C: &[[f64; 5]; 5], i: usize, j: usize| dot(&C[i], &C[j]);
        let before: [[f64; 5]; 5] =
            core::array::from_fn(|i| core::array::from_fn(|j| gram(&C, i, j)));
        // Ci = C^-1 by forward substitution, column by column.
        let mut Ci = [[0.0f64; 5]; 5];
        for j in 0..5 {
            for i in j..5 {
                let mut acc = if i == j { 1.0 } else { 0.0 };
                for k in j..i {
                    acc -= C[i][k] * Ci[k][j];
                }
                Ci[i][j] = acc / C[i][i];
            }
        }
        // Row i of the factor is column i of the storage.
        let mut Cm = nalgebra::SMatrix::<f64, 5, 5>::from_array_storage(nalgebra::ArrayStorage(C));
        let mut Cim =
            nalgebra::SMatrix::<f64, 5, 5>::from_array_storage(nalgebra::ArrayStorage(Ci));
        chol_drop(&mut Cm, &mut Cim, 5, l);
        let (C, Ci) = (Cm.data.0, Cim.data.0);
        let keep: [usize; 4] = core::array::from_fn(|k| if k < l { k } else { k + 1 });
        for (a, &i) in keep.iter().enumerate() {
            assert!(C[a][a] > 0.0);
            for (b, &j) in keep.iter().enumerate() {
                if b > a {
                    assert_eq!(C[a][b], 0.0, "upper triangle");
                    assert_eq!(Ci[a][b], 0.0, "upper triangle of the inverse");
                }
                assert!((gram(&C, a, b) - before[i][j]).abs() < 1e-12);
                // (C Ci)_ab = delta_ab
                let cci: f64 = (0..4).map(|k| C[a][k] * Ci[k][b]).sum();
                assert!((cci - f64::from(u8::from(a == b))).abs() < 1e-12);
            }
        }
        assert_eq!(Ci[4], [0.0; 5]);
        assert_eq!(C[4], [0.0; 5]);
    }
}
