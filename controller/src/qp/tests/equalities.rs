//! Equality rows (`DenseQp::push_equality`): held active from the start,
//! never dropped, multipliers of either sign; dependent ones either
//! redundant or a Farkas certificate; refused below `HOT_START_MIN_NV`
//! variables, where they are not compiled in.

use super::{assert_certificate, uniform};
use crate::qp::{DenseQp, DualActiveSet, HOT_START_MIN_NV, QpSettings, QpSolution, QpStatus};
use nalgebra::{SMatrix, SVector};

const N: usize = 16;
const C: usize = 48;

fn solver() -> DualActiveSet<N, C> {
    // 1/2 |x|^2 * 2 (H = 2I).
    DualActiveSet::new(&(SMatrix::identity() * 2.0), QpSettings::default()).unwrap()
}

fn e(i: usize) -> SVector<f64, N> {
    SVector::from_fn(|k, _| if k == i { 1.0 } else { 0.0 })
}

/// Stationarity `Hx + q + G'lambda = 0`, equality rows held, inequality rows
/// and their multipliers of the right sign, complementarity.
fn assert_kkt(s: &DualActiveSet<N, C>, qp: &DenseQp<N, C>, sol: &QpSolution<N, C>) {
    assert_eq!(sol.status, QpStatus::Solved);
    let mut stat = s.hessian() * sol.x + qp.q;
    // Relative to the sizes of the terms that cancel.
    let scale = 1.0 + qp.q.amax() + (s.hessian() * sol.x).amax() + sol.lambda.amax();
    for i in 0..qp.m {
        let (g, h) = qp.get_row(i).unwrap();
        let slack = h - g.dot(&sol.x);
        let tol = 1e-9 * (1.0 + h.abs() + g.amax() * sol.x.amax());
        if i < qp.me {
            assert!(slack.abs() <= tol, "equality {i} off by {slack}");
        } else {
            assert!(sol.lambda[i] >= 0.0);
            assert!(slack >= -tol, "row {i} violated by {slack}");
            assert!(
                (sol.lambda[i] * slack).abs() <= tol * (1.0 + sol.lambda[i]),
                "complementarity of row {i}: lambda {}, slack {slack}",
                sol.lambda[i]
            );
        }
        stat += g * sol.lambda[i];
    }
    assert!(stat.amax() <= 1e-9 * scale, "stationarity {stat:?}");
}

#[test]
fn equalities_hold_with_multipliers_of_either_sign() {
    // min |x - c|^2 with x0 + x1 = 1 and x2 = 3 (c = 1 everywhere):
    // x0 = x1 = 0.5 (lambda = 1 > 0), x2 = 3 (lambda = -4 < 0).
    let s = solver();
    let mut qp = DenseQp::<N, C>::with_q(SVector::repeat(-2.0));
    qp.push_equality(&(e(0) + e(1)), 1.0).unwrap();
    qp.push_equality(&e(2), 3.0).unwrap();
    let sol = s.solve(&qp, &[]);
    assert_kkt(&s, &qp, &sol);
    assert!((sol.x[0] - 0.5).abs() < 1e-14 && (sol.x[2] - 3.0).abs() < 1e-14);
    assert!((sol.lambda[0] - 1.0).abs() < 1e-12, "{}", sol.lambda[0]);
    assert!((sol.lambda[1] + 4.0).abs() < 1e-12, "{}", sol.lambda[1]);
    assert_eq!(sol.active_set(), &[0, 1]);
    assert_eq!(sol.iterations, 2);
    // An inequality row cannot be pushed before an equality row.
    qp.push_row(&e(3), 0.0).unwrap();
    assert!(qp.push_equality(&e(4), 0.0).is_err());
}

#[test]
fn an_equality_is_never_dropped() {
    // x0 = 1 (multiplier would have to turn negative to leave it) with
    // x0 + x1 <= 0 and a pull of x1 upwards: the inequality pushes x1 to -1
    // and the equality stays, its multiplier free.
    let s = solver();
    let mut q = SVector::<f64, N>::zeros();
    q[0] = 10.0; // pulls x0 to -5
    q[1] = -4.0; // pulls x1 to 2
    let mut qp = DenseQp::<N, C>::with_q(q);
    qp.push_equality(&e(0), 1.0).unwrap();
    qp.push_row(&(e(0) + e(1)), 0.0).unwrap();
    let sol = s.solve(&qp, &[]);
    assert_kkt(&s, &qp, &sol);
    assert!((sol.x[0] - 1.0).abs() < 1e-14);
    assert!((sol.x[1] + 1.0).abs() < 1e-14);
    assert!(sol.lambda[0] < 0.0, "{}", sol.lambda[0]);
    assert_eq!(sol.active_set(), &[0, 1]);
}

#[test]
fn dependent_equalities_are_redundant_or_certified_infeasible() {
    let s = solver();
    let q = SVector::<f64, N>::repeat(-2.0);
    // x0 + x1 = 1, x0 - x1 = 0, 2 x0 = 1: the third is implied.
    let mut qp = DenseQp::<N, C>::with_q(q);
    qp.push_equality(&(e(0) + e(1)), 1.0).unwrap();
    qp.push_equality(&(e(0) - e(1)), 0.0).unwrap();
    qp.push_equality(&(e(0) * 2.0), 1.0).unwrap();
    let sol = s.solve(&qp, &[]);
    assert_kkt(&s, &qp, &sol);
    assert_eq!(sol.active_set(), &[0, 1]);
    // ... and 2 x0 = 3 contradicts them, from above or from below.
    for (rhs, sign) in [(3.0, -1.0), (-1.0, 1.0)] {
        let mut bad = qp.clone();
        bad.h[2] = rhs;
        let sol = s.solve(&bad, &[]);
        assert_eq!(sol.status, QpStatus::Infeasible);
        assert_eq!(sol.lambda[2], sign);
        assert_certificate(&bad, &sol.lambda);
    }
}

#[test]
fn equalities_against_inequalities_are_certified_infeasible() {
    // x0 = 2 with x0 <= 1: the inequality cannot be added.
    let s = solver();
    let mut qp = DenseQp::<N, C>::with_q(SVector::zeros());
    qp.push_equality(&e(0), 2.0).unwrap();
    qp.push_row(&e(0), 1.0).unwrap();
    let sol = s.solve(&qp, &[]);
    assert_eq!(sol.status, QpStatus::Infeasible);
    assert_certificate(&qp, &sol.lambda);
    // A zero equality row with h != 0 is infeasible at once; with h = 0 it
    // holds.
    let mut z = DenseQp::<N, C>::with_q(SVector::zeros());
    z.push_equality(&SVector::zeros(), 1.0).unwrap();
    let sol = s.solve(&z, &[]);
    assert_eq!((sol.status, sol.lambda[0]), (QpStatus::Infeasible, -1.0));
    z.h[0] = 0.0;
    assert_eq!(s.solve(&z, &[]).status, QpStatus::Solved);
}

#[test]
fn random_qps_with_equalities_satisfy_kkt_and_hot_starts_agree() {
    let mut rnd = uniform(41);
    let (mut solved, mut infeasible) = (0, 0);
    for k in 0..200 {
        let a = SMatrix::<f64, N, N>::from_fn(|_, _| rnd());
        let s = DualActiveSet::<N, C>::new(
            &(a.transpose() * a + SMatrix::identity() * 4.0),
            QpSettings::default(),
        )
        .unwrap();
        let x0 = SVector::<f64, N>::from_fn(|_, _| rnd());
        let mut qp = DenseQp::<N, C>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
        let me = 1 + k % 6;
        for _ in 0..me {
            let g = SVector::<f64, N>::from_fn(|_, _| rnd());
            qp.push_equality(&g, g.dot(&x0)).unwrap();
        }
        for j in 0..30 {
            let g = SVector::<f64, N>::from_fn(|_, _| rnd());
            // Every 7th QP: a row that x0 violates by far (often infeasible).
            let slack = if k % 7 == 0 && j == 0 {
                -3.0
            } else {
                0.2 * rnd().abs()
            };
            qp.push_row(&g, g.dot(&x0) + slack).unwrap();
        }
        let cold = s.without_hot_start().solve(&qp, &[]);
        let mut prefer = [false; C];
        for &a in cold.active_set() {
            prefer[usize::from(a)] = true;
        }
        let hot = s.solve(&qp, &prefer);
        assert_eq!(cold.status, hot.status, "{k}");
        match cold.status {
            QpStatus::Solved => {
                solved += 1;
                assert_kkt(&s, &qp, &cold);
                assert_kkt(&s, &qp, &hot);
                assert!((cold.x - hot.x).amax() < 1e-9);
                // The equality rows lead the active list.
                assert!(
                    cold.active_set()[..me]
                        .iter()
                        .enumerate()
                        .all(|(i, &a)| usize::from(a) == i)
                );
            }
            QpStatus::Infeasible => {
                infeasible += 1;
                assert_certificate(&qp, &cold.lambda);
                assert_certificate(&qp, &hot.lambda);
            }
            other => panic!("{k}: {other:?}"),
        }
    }
    assert!(
        solved > 100 && infeasible > 5,
        "{solved} solved, {infeasible} infeasible"
    );
}

#[test]
fn small_static_sizes_refuse_equalities() {
    const { assert!(6 < HOT_START_MIN_NV) };
    let s = DualActiveSet::<6, 8>::new(&SMatrix::identity(), QpSettings::default()).unwrap();
    let mut qp = DenseQp::<6, 8>::default();
    qp.push_equality(&SVector::repeat(1.0), 1.0).unwrap();
    assert_eq!(s.solve(&qp, &[]).status, QpStatus::NumericalError);
}
