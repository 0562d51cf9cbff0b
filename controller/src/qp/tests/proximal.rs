//! Positive semidefinite Hessians: the proximal-point iterations
//! (`qp/proximal.rs`) in the static and the run-time-sized instances, the
//! least-distance path's answer, the refusal where they are not compiled in.

use crate::ldp::LdpSolver;
use crate::qp::{
    DenseQp, DualActiveSet, HessianError, PROX_EPS, PROX_MAX_OUTER, QpSettings, QpStatus,
};
use nalgebra::{SMatrix, SVector};

const N: usize = 16;
const C: usize = 48;

/// `H = diag(w)`: weight 2 on the even variables, 0 on the odd ones.
fn hessian() -> SMatrix<f64, N, N> {
    SMatrix::from_fn(|i, j| if i == j && i % 2 == 0 { 2.0 } else { 0.0 })
}

fn e(i: usize) -> SVector<f64, N> {
    SVector::from_fn(|k, _| if k == i { 1.0 } else { 0.0 })
}

/// `min sum_even (x_i^2 - 2 c_i x_i) + sum_odd d_i x_i` with every variable
/// in `[-1, 1]` and the equality `x_1 + x_3 = 0.5`: the even variables go to
/// `clamp(c_i)`, the odd ones (a linear cost) to a bound, except `x_1` and
/// `x_3`, which share the equality (`d_1 < d_3`: `x_3` at its lower bound
/// `-0.5`... see the assertions).
fn problem() -> (DenseQp<N, C>, SVector<f64, N>) {
    let c = [0.3, 1.7, -0.4, -2.5, 0.9, 0.1, -0.8, 0.6];
    let d = [1.0, 2.0, -0.5, 0.25, -3.0, 1.5, -1.0, 0.75];
    let mut q = SVector::<f64, N>::zeros();
    let mut want = SVector::<f64, N>::zeros();
    for k in 0..N / 2 {
        q[2 * k] = -2.0 * c[k];
        want[2 * k] = c[k].clamp(-1.0, 1.0);
        q[2 * k + 1] = d[k];
        want[2 * k + 1] = -d[k].signum();
    }
    // x_1 + x_3 = 0.5 with d_1 = 1 < d_3 = 2: x_3 as low as the bound
    // lets it, x_1 = 0.5 - x_3 in [-1, 1] => x_3 = -0.5, x_1 = 1.
    want[1] = 1.0;
    want[3] = -0.5;
    let mut qp = DenseQp::<N, C>::with_q(q);
    qp.push_equality(&(e(1) + e(3)), 0.5).unwrap();
    for i in 0..N {
        qp.push_row(&e(i), 1.0).unwrap();
        qp.push_row(&-e(i), 1.0).unwrap();
    }
    (qp, want)
}

#[test]
fn a_semidefinite_hessian_is_solved_by_proximal_iterations() {
    let s = DualActiveSet::<N, C>::new(&hessian(), QpSettings::default()).unwrap();
    assert_eq!(s.proximal_weight(), PROX_EPS * 2.0);
    let (qp, want) = problem();
    let sol = s.solve(&qp, &[]);
    assert_eq!(sol.status, QpStatus::Solved);
    assert!((sol.x - want).amax() < 1e-8, "{:?}", sol.x - want);
    // Stationarity of the QP itself, to the proximal residual.
    let mut stat = s.hessian() * sol.x + qp.q;
    for i in 0..qp.m {
        stat += qp.row(i) * sol.lambda[i];
    }
    assert!(stat.amax() < 1e-8, "{stat:?}");
    let objective = 0.5 * sol.x.dot(&(s.hessian() * sol.x)) + qp.q.dot(&sol.x);
    assert!((sol.objective - objective).abs() < 1e-12 * objective.abs());
    // The proximal solves after the first resume from its active set
    // (`qp/resolve.rs`): one iteration per active row (the first solve
    // enters them), none more.
    assert_eq!(sol.iterations, sol.n_active as u32);
    // The other entry points take the same path, bit for bit (the
    // least-distance path's without the hot start, as always).
    let rows = s.prepare_rows(&qp);
    let prepared = s.solve_prepared(&qp, &rows, &[]);
    let ldp = LdpSolver::prepare(&s, &qp).solve_qp(&qp, &[]);
    let cold = s.without_hot_start().solve(&qp, &[]);
    assert!((cold.x - want).amax() < 1e-8, "{:?}", cold.x - want);
    for (a, b) in [(&prepared, &sol), (&ldp, &cold)] {
        assert_eq!(a.iterations, b.iterations);
        assert!(
            a.x.iter()
                .zip(b.x.iter())
                .all(|(u, v)| u.to_bits() == v.to_bits())
        );
    }
    // The run-time-sized instance runs the same code: the same bits.
    #[cfg(feature = "alloc")]
    {
        use crate::qp::{DenseQpDyn, DualActiveSetDyn};
        let h = nalgebra::DMatrix::from_column_slice(N, N, hessian().as_slice());
        let sd = DualActiveSetDyn::new(&h, QpSettings::default()).unwrap();
        let mut qd =
            DenseQpDyn::with_capacity(nalgebra::DVector::from_column_slice(qp.q.as_slice()), C);
        for (i, (g, hi)) in qp.rows().enumerate() {
            let g = nalgebra::DVector::from_column_slice(g.as_slice());
            if i < qp.me {
                qd.push_equality(&g, hi).unwrap();
            } else {
                qd.push_row(&g, hi).unwrap();
            }
        }
        let d = sd.solve(&qd, &[]);
        assert_eq!((d.status, d.iterations), (sol.status, sol.iterations));
        assert!(
            d.x.iter()
                .zip(sol.x.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }
}

#[test]
fn the_budget_covers_every_proximal_solve() {
    let (qp, _) = problem();
    let s = DualActiveSet::<N, C>::new(&hessian(), QpSettings::default()).unwrap();
    let full = s.solve(&qp, &[]).iterations;
    for budget in [1, full / 2, full - 1] {
        let sol = s.with_max_iter(budget).solve(&qp, &[]);
        assert_eq!(sol.status, QpStatus::IterationLimit, "{budget}");
        assert!(sol.iterations <= budget, "{} > {budget}", sol.iterations);
    }
    assert_eq!(
        s.with_max_iter(full).solve(&qp, &[]).status,
        QpStatus::Solved
    );
}

#[test]
fn an_objective_unbounded_below_ends_at_the_iteration_limit() {
    // x_1 has no weight and no row: 1/2 x_0^2 + x_1 has no minimum.
    let s = DualActiveSet::<N, C>::new(&hessian(), QpSettings::default()).unwrap();
    let qp = DenseQp::<N, C>::with_q(e(1));
    let sol = s.solve(&qp, &[]);
    assert_eq!(sol.status, QpStatus::IterationLimit);
    // The iterates walk down the objective, one proximal step
    // (`|q| / eps`) per solve.
    let eps = s.proximal_weight();
    assert!((sol.x[1] + f64::from(PROX_MAX_OUTER) / eps).abs() < 1e-6 / eps);
}

#[test]
fn an_empty_feasible_set_is_found_as_for_a_definite_hessian() {
    let s = DualActiveSet::<N, C>::new(&hessian(), QpSettings::default()).unwrap();
    let mut qp = DenseQp::<N, C>::with_q(e(1));
    qp.push_row(&e(1), -1.0).unwrap();
    qp.push_row(&-e(1), -1.0).unwrap(); // x_1 <= -1 and x_1 >= 1
    let sol = s.solve(&qp, &[]);
    assert_eq!(sol.status, QpStatus::Infeasible);
    assert_eq!((sol.lambda[0], sol.lambda[1]), (1.0, 1.0));
}

#[test]
fn a_definite_hessian_has_no_proximal_weight() {
    let h = SMatrix::<f64, N, N>::identity();
    let s = DualActiveSet::<N, C>::new(&h, QpSettings::default()).unwrap();
    assert_eq!(s.proximal_weight(), 0.0);
}

#[test]
fn small_static_sizes_and_indefinite_hessians_are_refused() {
    // Below HOT_START_MIN_NV the iterations are not compiled in.
    let h = SMatrix::<f64, 2, 2>::new(1.0, 0.0, 0.0, 0.0);
    let e = DualActiveSet::<2, 4>::new(&h, QpSettings::default()).unwrap_err();
    assert_eq!(e, HessianError::NotPositiveDefinite);
    // Indefinite beyond the proximal weight: refused at any size.
    let mut h = hessian();
    h[(1, 1)] = -1e-3;
    let e = DualActiveSet::<N, C>::new(&h, QpSettings::default()).unwrap_err();
    assert_eq!(e, HessianError::NotPositiveDefinite);
}
