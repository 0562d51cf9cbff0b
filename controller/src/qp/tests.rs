//! Unit tests of the dual active-set solver.

use super::*;
use nalgebra::{Matrix2, SMatrix, SVector, Vector2};

mod bounds;
mod equalities;
mod hot_start;
mod proximal;
mod restart;

fn solver2() -> DualActiveSet<2, 4> {
    DualActiveSet::new(&Matrix2::new(2.0, 0.0, 0.0, 2.0), QpSettings::default()).unwrap()
}

#[test]
fn unconstrained_minimiser() {
    let s = solver2();
    let qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
    let sol = s.solve(&qp, &[false; 4]);
    assert_eq!(sol.status, QpStatus::Solved);
    assert!((sol.x - Vector2::new(1.0, 2.0)).amax() < 1e-14);
    assert_eq!(sol.iterations, 0);
    assert!((sol.objective - (-5.0)).abs() < 1e-14);
}

/// When the unconstrained minimiser satisfies every row, `solve` returns it
/// after the one pass over the rows, without an iteration (so even with a
/// budget of 0), bit for bit the minimiser of the QP without rows, whatever
/// the warm-start marks.
#[test]
fn feasible_unconstrained_minimiser_is_returned_after_one_pass() {
    let dense =
        DualActiveSet::<2, 4>::new(&Matrix2::new(3.0, 1.0, 1.0, 2.0), QpSettings::default())
            .unwrap();
    for s in [solver2(), dense] {
        let free = s.with_max_iter(0).solve(
            &DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0)),
            &[false; 4],
        );
        let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
        qp.push_row(&Vector2::new(1.0, 0.0), 5.0).unwrap();
        qp.push_row(&Vector2::new(0.0, 1.0), 3.0).unwrap();
        qp.push_row(&Vector2::new(1.0, 1.0), 4.0).unwrap();
        qp.push_row(&Vector2::new(-1.0, 0.0), 0.0).unwrap();
        assert!(qp.max_violation(&free.x) == 0.0);
        for prefer in [[false; 4], [true; 4]] {
            let sol = s.with_max_iter(0).solve(&qp, &prefer);
            assert_eq!(
                (sol.status, sol.iterations, sol.n_active),
                (QpStatus::Solved, 0, 0)
            );
            assert_eq!(sol.x.map(f64::to_bits), free.x.map(f64::to_bits));
            assert_eq!(sol.lambda, SVector::<f64, 4>::zeros());
        }
    }
}

#[test]
fn one_active_bound_and_multiplier() {
    // min (x-1)^2 + (y-2)^2, s.t. x + y <= 1  -> x = 0, y = 1, lambda = 2.
    let s = solver2();
    let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
    qp.push_row(&Vector2::new(1.0, 1.0), 1.0).unwrap();
    let sol = s.solve(&qp, &[false; 4]);
    assert_eq!(sol.status, QpStatus::Solved);
    assert!((sol.x - Vector2::new(0.0, 1.0)).amax() < 1e-14);
    assert!((sol.lambda[0] - 2.0).abs() < 1e-14);
    assert_eq!(sol.active_set(), &[0]);
}

#[test]
fn drop_happens_and_result_is_optimal() {
    // min (x-1)^2 + (y-2)^2 with y <= 0 and x <= -1, x + y <= -2 (redundant-ish)
    let s = solver2();
    let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
    qp.push_row(&Vector2::new(1.0, 1.0), -2.0).unwrap();
    qp.push_row(&Vector2::new(0.0, 1.0), 0.0).unwrap();
    qp.push_row(&Vector2::new(1.0, 0.0), -1.0).unwrap();
    let sol = s.solve(&qp, &[false; 4]);
    assert_eq!(sol.status, QpStatus::Solved);
    // Projection of (1, 2) onto {x + y <= -2}: (-1.5, -0.5), which satisfies
    // the other two rows.
    assert!(
        (sol.x - Vector2::new(-1.5, -0.5)).amax() < 1e-12,
        "{:?}",
        sol.x
    );
    assert!(qp.max_violation(&sol.x) < 1e-12);
    let grad = s.hessian() * sol.x + qp.q;
    let mut stat = grad;
    for i in 0..qp.m {
        stat += qp.row(i) * sol.lambda[i];
        assert!(sol.lambda[i] >= 0.0);
    }
    assert!(stat.amax() < 1e-12);
}

/// Checks a Farkas certificate: y >= 0 (entries of equality rows of either
/// sign), |G'y| small, h'y < 0.
fn assert_certificate<const NV: usize, const NC: usize>(
    qp: &DenseQp<NV, NC>,
    y: &SVector<f64, NC>,
) {
    let mut gty = SVector::<f64, NV>::zeros();
    let mut hty = 0.0;
    for i in 0..qp.m {
        assert!(i < qp.me || y[i] >= 0.0, "inequality entry {i} = {}", y[i]);
        gty += qp.row(i) * y[i];
        hty += qp.h[i] * y[i];
    }
    assert!(gty.amax() <= 1e-12 * (1.0 + y.amax()), "G'y = {gty:?}");
    assert!(hty < 0.0, "h'y = {hty}");
}

#[test]
fn infeasible_detected() {
    let s = solver2();
    let mut qp = DenseQp::<2, 4>::default();
    qp.push_row(&Vector2::new(1.0, 0.0), -1.0).unwrap(); // x <= -1
    qp.push_row(&Vector2::new(-1.0, 0.0), -1.0).unwrap(); // x >= 1
    let sol = s.solve(&qp, &[false; 4]);
    assert_eq!(sol.status, QpStatus::Infeasible);
    assert_certificate(&qp, &sol.lambda);
    // Three rows, one of them irrelevant: x + y <= -1, x >= 0, y >= 0.
    let mut qp = DenseQp::<2, 4>::default();
    qp.push_row(&Vector2::new(0.0, 1.0), 5.0).unwrap();
    qp.push_row(&Vector2::new(1.0, 1.0), -1.0).unwrap();
    qp.push_row(&Vector2::new(-1.0, 0.0), 0.0).unwrap();
    qp.push_row(&Vector2::new(0.0, -1.0), 0.0).unwrap();
    let sol = s.solve(&qp, &[false; 4]);
    assert_eq!(sol.status, QpStatus::Infeasible);
    assert_certificate(&qp, &sol.lambda);
    assert_eq!(sol.lambda[0], 0.0);
}

#[test]
fn zero_row_negative_rhs_is_infeasible() {
    let s = solver2();
    let mut qp = DenseQp::<2, 4>::default();
    qp.push_row(&Vector2::new(0.0, 0.0), -1.0).unwrap();
    assert_eq!(s.solve(&qp, &[false; 4]).status, QpStatus::Infeasible);
    let mut qp = DenseQp::<2, 4>::default();
    qp.push_row(&Vector2::new(0.0, 0.0), 1.0).unwrap();
    assert_eq!(s.solve(&qp, &[false; 4]).status, QpStatus::Solved);
}

/// A zero row that holds only to the tolerance (`-tol <= h_i < 0`) is never
/// added (its rate in the scan is `+0`): the solve gives the bits of the one
/// without it, with or without a mark on it.
#[test]
fn zero_row_within_tolerance_is_never_added() {
    let s = solver2();
    let tol = QpSettings::default().tol_primal;
    let mut without = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
    without.push_row(&Vector2::new(1.0, 1.0), 1.0).unwrap();
    let want = s.solve(&without, &[false; 4]);
    assert_eq!(want.status, QpStatus::Solved);
    assert_eq!(want.iterations, 1);
    let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
    qp.push_row(&Vector2::new(0.0, 0.0), -0.5 * tol).unwrap();
    qp.push_row(&Vector2::new(1.0, 1.0), 1.0).unwrap();
    qp.push_row(&Vector2::new(0.0, 0.0), -tol).unwrap();
    for marks in [[false; 4], [true, false, true, false], [true; 4]] {
        let sol = s.solve(&qp, &marks);
        assert_eq!(sol.status, QpStatus::Solved);
        assert_eq!(sol.iterations, want.iterations);
        assert_eq!(sol.x.map(f64::to_bits), want.x.map(f64::to_bits));
        assert_eq!(sol.lambda[0].to_bits(), 0);
        assert_eq!(sol.lambda[1].to_bits(), want.lambda[0].to_bits());
        assert_eq!(sol.lambda[2].to_bits(), 0);
        assert_eq!(sol.active_set(), &[1]);
    }
}

/// The bare-metal scan's rate of a zero row that does not hold: its
/// `1 / |L^-1 g|` is `-0` (cached: not `+0`), so `slack * -0` is `+0`.
#[test]
fn zero_row_rates_plus_zero() {
    let s = solver2();
    let ihn = s.inv_hnorm(&[0.0, 0.0], 0.0);
    assert_eq!(ihn.to_bits(), (-0.0f64).to_bits());
    assert_eq!((-0.5e-10 * ihn).to_bits(), 0);
    assert!(s.inv_hnorm(&[1.0, 0.0], 1.0) > 0.0);
}

#[test]
fn budget_is_respected() {
    let s = solver2();
    let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
    qp.push_row(&Vector2::new(1.0, 1.0), -2.0).unwrap();
    qp.push_row(&Vector2::new(0.0, 1.0), -1.0).unwrap();
    let full = s.solve(&qp, &[false; 4]);
    assert_eq!(full.status, QpStatus::Solved);
    assert_eq!(full.iterations, 2);
    let sol = s.with_max_iter(1).solve(&qp, &[false; 4]);
    assert_eq!(sol.status, QpStatus::IterationLimit);
    assert_eq!(sol.iterations, 1);
    let sol = s.with_max_iter(0).solve(&qp, &[false; 4]);
    assert_eq!(sol.status, QpStatus::IterationLimit);
    assert_eq!(sol.iterations, 0);
}

#[test]
fn non_finite_data_is_numerical_error() {
    let s = solver2();
    let qp = DenseQp::<2, 4>::with_q(Vector2::new(f64::NAN, 0.0));
    assert_eq!(s.solve(&qp, &[false; 4]).status, QpStatus::NumericalError);
}

#[test]
fn bad_hessians_rejected() {
    let e = DualActiveSet::<2, 4>::new(&Matrix2::new(1.0, 0.0, 0.0, -1.0), QpSettings::default());
    assert_eq!(e.unwrap_err(), HessianError::NotPositiveDefinite);
    let e = DualActiveSet::<2, 4>::new(&Matrix2::new(1.0, 0.5, 0.0, 1.0), QpSettings::default());
    assert_eq!(e.unwrap_err(), HessianError::NotSymmetric);
    // Every pair is compared: an asymmetry in any one off-diagonal pair of a
    // 6 x 6 Hessian is found, on either side of the diagonal.
    for (i, j) in [(4, 2), (2, 4), (5, 0), (0, 5), (1, 0)] {
        let mut h = SMatrix::<f64, 6, 6>::identity() * 2.0;
        h[(i, j)] = 1e-6;
        let e = DualActiveSet::<6, 4>::new(&h, QpSettings::default());
        assert_eq!(e.unwrap_err(), HessianError::NotSymmetric, "({i}, {j})");
    }
    let e = DualActiveSet::<2, 4>::new(
        &Matrix2::new(f64::NAN, 0.0, 0.0, 1.0),
        QpSettings::default(),
    );
    assert_eq!(e.unwrap_err(), HessianError::NotFinite);
}

#[test]
fn prepared_rows_give_the_same_solve() {
    // A non-diagonal Hessian (dense path) and the diagonal one (fast path).
    let dense =
        DualActiveSet::<2, 4>::new(&Matrix2::new(3.0, 1.0, 1.0, 2.0), QpSettings::default())
            .unwrap();
    for s in [dense, solver2()] {
        let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
        qp.push_row(&Vector2::new(1.0, 1.0), -2.0).unwrap();
        qp.push_row(&Vector2::new(0.0, 1.0), 0.0).unwrap();
        qp.push_row(&Vector2::new(1.0, 0.0), -1.0).unwrap();
        let rows = s.prepare_rows(&qp);
        let cold = s.solve(&qp, &[false; 4]);
        assert_eq!(cold.status, QpStatus::Solved);
        // KKT: H x + q + G' lambda = 0, lambda >= 0, rows hold.
        let mut stat = s.hessian() * cold.x + qp.q;
        for i in 0..qp.m {
            stat += qp.row(i) * cold.lambda[i];
            assert!(cold.lambda[i] >= 0.0);
        }
        assert!(stat.amax() < 1e-12, "{stat:?}");
        assert!(qp.max_violation(&cold.x) < 1e-12);
        // Same G, other h and q: the prepared rows still apply.
        qp.h[0] = -3.0;
        qp.q = Vector2::new(1.0, -1.0);
        let a = s.solve(&qp, &[false; 4]);
        let b = s.solve_prepared(&qp, &rows, &[false; 4]);
        assert_eq!(a.status, b.status);
        assert_eq!(a.iterations, b.iterations);
        assert_eq!(a.x, b.x);
        // Rows prepared for another row count are refused.
        qp.push_row(&Vector2::new(-1.0, 0.0), 5.0).unwrap();
        let c = s.solve_prepared(&qp, &rows, &[false; 4]);
        assert_eq!(c.status, QpStatus::NumericalError);
    }
}

/// KKT conditions of a solution, or the certificate of an infeasible QP.
fn assert_kkt<const NV: usize, const NC: usize>(
    s: &DualActiveSet<NV, NC>,
    qp: &DenseQp<NV, NC>,
    sol: &QpSolution<NV, NC>,
) {
    match sol.status {
        QpStatus::Solved => {
            let mut stat = s.hessian() * sol.x + qp.q;
            for i in 0..qp.m {
                let (g, h) = qp.get_row(i).unwrap();
                let slack = h - g.dot(&sol.x);
                assert!(sol.lambda[i] >= 0.0);
                assert!(slack >= -1e-9, "row {i} violated by {slack}");
                assert!((sol.lambda[i] * slack).abs() < 1e-9, "complementarity");
                stat += g * sol.lambda[i];
            }
            assert!(stat.amax() < 1e-9, "stationarity {stat:?}");
        }
        QpStatus::Infeasible => assert_certificate(qp, &sol.lambda),
        other => panic!("unexpected status {other:?}"),
    }
}

/// Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG, top bits).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

#[test]
fn diagonal_and_dense_hessians_satisfy_kkt_on_random_qps() {
    // Deterministic pseudo-random QPs (64-bit LCG), both Hessian code paths.
    let mut rnd = uniform(0x2545_f491_4f6c_dd1d);
    let (mut solved, mut infeasible) = (0, 0);
    for k in 0..400 {
        let H = if k % 2 == 0 {
            SMatrix::<f64, 6, 6>::from_diagonal(&SVector::from_fn(|_, _| 0.1 + 10.0 * rnd().abs()))
        } else {
            let A = SMatrix::<f64, 6, 6>::from_fn(|_, _| rnd());
            A.transpose() * A + SMatrix::identity() * 0.1
        };
        let s = DualActiveSet::<6, 24>::new(&H, QpSettings::default()).unwrap();
        assert_eq!(s.linv_diag, k % 2 == 0);
        let mut qp = DenseQp::<6, 24>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
        for _ in 0..(4 + k % 20) {
            let g = SVector::<f64, 6>::from_fn(|_, _| rnd());
            qp.push_row(&g, rnd() + 0.3).unwrap();
        }
        let sol = s.solve(&qp, &[false; 24]);
        assert_kkt(&s, &qp, &sol);
        let rows = s.prepare_rows(&qp);
        let prepared = s.solve_prepared(&qp, &rows, &[false; 24]);
        assert_eq!(prepared.x, sol.x);
        solved += usize::from(sol.status.is_solved());
        infeasible += usize::from(sol.status.is_infeasible());
    }
    // Both outcomes are exercised.
    assert!(
        solved > 100 && infeasible > 10,
        "{solved} solved, {infeasible} infeasible"
    );
}

/// `solve_selected` (in place) is bit for bit `solve` on the compacted QP,
/// and so is the provided `QpBackend::solve_selected` (which compacts),
/// with multipliers, active set and warm-start marks mapped between the two
/// row numberings; a non-finite right-hand side of a left-out row is
/// ignored.
#[test]
fn solve_selected_is_solve_on_the_selected_rows() {
    struct Compacting;
    impl QpBackend<6, 24> for Compacting {
        fn solve_qp(
            &mut self,
            solver: &DualActiveSet<6, 24>,
            qp: &DenseQp<6, 24>,
            prefer: &[bool; 24],
        ) -> QpSolution<6, 24> {
            solver.solve(qp, prefer)
        }
    }
    let mut rnd = uniform(0x0bad_5eed_1234_5678);
    let (mut solved, mut infeasible) = (0, 0);
    for k in 0..400 {
        let H = SMatrix::<f64, 6, 6>::identity() * 2.0;
        let s = DualActiveSet::<6, 24>::new(&H, QpSettings::default()).unwrap();
        let mut qp = DenseQp::<6, 24>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
        let mut h = SVector::<f64, 24>::zeros();
        let mut enabled = [false; 24];
        let mut prefer = [false; 24];
        let mut sub = DenseQp::<6, 24>::with_q(qp.q);
        let mut sub_prefer = [false; 24];
        let mut orig = [0usize; 24];
        for i in 0..(4 + k % 20) {
            let g = SVector::<f64, 6>::from_fn(|_, _| rnd());
            qp.push_row(&g, 7.0).unwrap();
            enabled[i] = rnd() < 0.5;
            prefer[i] = rnd() < -0.6;
            h[i] = if enabled[i] { rnd() + 0.3 } else { f64::NAN };
            if enabled[i] {
                orig[sub.m] = i;
                sub_prefer[sub.m] = prefer[i];
                sub.push_row(&g, h[i]).unwrap();
            }
        }
        let want = s.solve(&sub, &sub_prefer);
        for got in [
            s.solve_selected(&qp, &h, &enabled, &prefer, 200),
            Compacting.solve_selected(&s, &qp, &h, &enabled, &prefer, 200),
        ] {
            assert_eq!(got.status, want.status);
            assert_eq!(got.iterations, want.iterations);
            assert_eq!(got.x.map(f64::to_bits), want.x.map(f64::to_bits));
            assert_eq!(got.objective.to_bits(), want.objective.to_bits());
            let mut lambda = SVector::<f64, 24>::zeros();
            for j in 0..sub.m {
                lambda[orig[j]] = want.lambda[j];
            }
            assert_eq!(got.lambda.map(f64::to_bits), lambda.map(f64::to_bits));
            assert_eq!(got.n_active, want.n_active);
            for (&g, &w) in got.active_set().iter().zip(want.active_set()) {
                assert_eq!(usize::from(g), orig[usize::from(w)]);
            }
        }
        solved += usize::from(want.status.is_solved());
        infeasible += usize::from(want.status.is_infeasible());
    }
    assert!(
        solved > 100 && infeasible > 10,
        "{solved} solved, {infeasible} infeasible"
    );
}

#[test]
fn overflowing_row_norm_is_numerical_error() {
    let s = solver2();
    let mut qp = DenseQp::<2, 4>::default();
    qp.push_row(&Vector2::new(1e200, 0.0), 1.0).unwrap();
    assert_eq!(s.solve(&qp, &[false; 4]).status, QpStatus::NumericalError);
}

#[test]
fn warm_start_marks_do_not_change_solution() {
    let s = solver2();
    let mut qp = DenseQp::<2, 4>::with_q(Vector2::new(-2.0, -4.0));
    qp.push_row(&Vector2::new(1.0, 1.0), -2.0).unwrap();
    qp.push_row(&Vector2::new(0.0, 1.0), 0.0).unwrap();
    qp.push_row(&Vector2::new(1.0, 0.0), -1.0).unwrap();
    let cold = s.solve(&qp, &[false; 4]);
    // Wrong guesses cost iterations but not accuracy.
    let wrong = s.solve(&qp, &[false, true, true, false]);
    assert_eq!(wrong.status, QpStatus::Solved);
    assert!((cold.x - wrong.x).amax() < 1e-12);
    assert!(wrong.iterations > cold.iterations);
    // The right guess is never slower.
    let right = s.solve(&qp, &[true, false, false, false]);
    assert!((cold.x - right.x).amax() < 1e-12);
    assert!(right.iterations <= cold.iterations);
}
