//! The solver's hot start (`QpSettings::hot_start`, on by default): the rows
//! marked in `prefer` enter the active set together before the first row scan.
//! It may change the path, never the answer: on random QPs with marks that are
//! right, partly right, wrong or all rows, the hot and the cold solve agree on
//! the status, on `x` and the objective (solved; KKT checked) and both give a
//! valid Farkas certificate (infeasible). With the optimal active set marked
//! (and no degenerate multiplier) the hot start solves with one add per active
//! row and no other iteration. Budgets are kept.

use super::{assert_certificate, assert_kkt, uniform};
use crate::qp::{DenseQp, DualActiveSet, HOT_START_MIN_NV, QpSettings, QpStatus};
use nalgebra::{SMatrix, SVector};

fn hessian<const NV: usize>(rnd: &mut impl FnMut() -> f64, diagonal: bool) -> SMatrix<f64, NV, NV> {
    if diagonal {
        SMatrix::from_diagonal(&SVector::from_fn(|_, _| 0.1 + 10.0 * rnd().abs()))
    } else {
        let a = SMatrix::<f64, NV, NV>::from_fn(|_, _| rnd());
        a.transpose() * a + SMatrix::identity() * 0.1
    }
}

/// Counts of what the family exercised, so the test fails if it stops covering
/// a case.
#[derive(Default, Debug)]
struct Seen {
    solved: usize,
    infeasible: usize,
    exact_marks: usize,
    /// Solves where the hot and the cold path took a different number of
    /// iterations: the hot start ran.
    other_path: usize,
}

fn family<const NV: usize, const NC: usize>(seed: u64, count: usize) -> Seen {
    let mut rnd = uniform(seed);
    let mut seen = Seen::default();
    for k in 0..count {
        let h = hessian::<NV>(&mut rnd, k % 2 == 0);
        let hot = DualActiveSet::<NV, NC>::new(&h, QpSettings::default()).unwrap();
        let cold = hot.without_hot_start();
        let mut qp = DenseQp::<NV, NC>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
        for _ in 0..(NV / 2 + k % (NC - NV / 2)) {
            let g = SVector::<f64, NV>::from_fn(|_, _| rnd());
            // A few duplicated and opposite rows: dependent marks.
            if k % 5 == 0 && qp.m > 2 && rnd() > 0.6 {
                let r = qp.row(qp.m - 1);
                let _ = qp.push_row(&(-r), rnd() + 0.3);
            }
            let _ = qp.push_row(&g, rnd() + 0.3);
        }
        let unmarked = [false; NC];
        let a = cold.solve(&qp, &unmarked);
        let optimal = {
            let mut p = [false; NC];
            for &i in a.active_set() {
                p[usize::from(i)] = true;
            }
            p
        };
        // Marks: the optimal set, a random subset, the optimal set plus random
        // rows, every row.
        let mut marks = [optimal, [false; NC], optimal, [false; NC]];
        for i in 0..qp.m {
            marks[1][i] = rnd() > 0.3;
            marks[2][i] |= rnd() > 0.7;
            marks[3][i] = true;
        }
        for (which, prefer) in marks.iter().enumerate() {
            let b = hot.solve(&qp, prefer);
            let c = cold.solve(&qp, prefer);
            assert_eq!(a.status, b.status, "qp {k}, marks {which}");
            assert_eq!(a.status, c.status, "qp {k}, marks {which}");
            if b.iterations != c.iterations {
                seen.other_path += 1;
            }
            match b.status {
                QpStatus::Solved => {
                    assert_kkt(&hot, &qp, &b);
                    let xs = a.x.amax().max(1.0);
                    assert!((a.x - b.x).amax() <= 1e-9 * xs, "qp {k} marks {which}");
                    let os = a.objective.abs().max(1.0);
                    assert!((a.objective - b.objective).abs() <= 1e-9 * os);
                    let degenerate = a
                        .active_set()
                        .iter()
                        .any(|&i| a.lambda[usize::from(i)] < 1e-6);
                    if which == 0 && !degenerate {
                        // One add per active row, no scan finds anything else.
                        assert_eq!(b.iterations as usize, a.n_active, "qp {k}");
                        seen.exact_marks += 1;
                    }
                }
                QpStatus::Infeasible => {
                    assert_certificate(&qp, &b.lambda);
                }
                other => panic!("qp {k}, marks {which}: {other:?}"),
            }
        }
        match a.status {
            QpStatus::Solved => seen.solved += 1,
            _ => seen.infeasible += 1,
        }
    }
    seen
}

#[test]
fn hot_start_changes_the_path_not_the_answer() {
    // Sizes with the hot start compiled in.
    const { assert!(HOT_START_MIN_NV <= 16) };
    let small = family::<16, 48>(0x2545_f491_4f6c_dd1d, 300);
    let large = family::<24, 96>(0x9e37_79b9_7f4a_7c15, 150);
    for s in [&small, &large] {
        assert!(s.solved > 20 && s.infeasible > 5, "{s:?}");
        assert!(s.exact_marks > 20 && s.other_path > 20, "{s:?}");
    }
}

#[test]
fn hot_start_keeps_the_budget() {
    let mut rnd = uniform(11);
    let h = hessian::<16>(&mut rnd, false);
    let s = DualActiveSet::<16, 48>::new(&h, QpSettings::default()).unwrap();
    let mut limited = 0;
    for _ in 0..50 {
        let mut qp = DenseQp::<16, 48>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
        for _ in 0..40 {
            let g = SVector::<f64, 16>::from_fn(|_, _| rnd());
            qp.push_row(&g, rnd() + 0.3).unwrap();
        }
        let all = [true; 48];
        for budget in 0..24 {
            let sol = s.with_max_iter(budget).solve(&qp, &all);
            assert!(sol.iterations <= budget);
            if sol.status == QpStatus::IterationLimit {
                limited += 1;
                assert!(sol.x.iter().all(|v| v.is_finite()));
            }
        }
    }
    assert!(limited > 50, "{limited} budget-limited solves");
}

/// A probe solved by the hot start's guess holds no factor of its active
/// rows (`J`, `R` are never formed for them), so the next probe of the
/// same rows must not resume from it: it starts from scratch and reaches
/// the optimum of its own `h`.
#[test]
fn a_probe_after_a_guessed_probe_reaches_its_own_optimum() {
    const NV: usize = 16;
    const NC: usize = 32;
    let mut rnd = uniform(41);
    let mut guessed = 0;
    for k in 0..40 {
        let h = hessian::<NV>(&mut rnd, k % 2 == 0);
        let hot = DualActiveSet::<NV, NC>::new(&h, QpSettings::default()).unwrap();
        let mut qp = DenseQp::<NV, NC>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
        for _ in 0..NC {
            let g = SVector::<f64, NV>::from_fn(|_, _| rnd());
            let _ = qp.push_row(&g, rnd() + 0.3);
        }
        let all = [true; NC];
        let unmarked = [false; NC];
        let a = hot.solve(&qp, &unmarked);
        if a.status != QpStatus::Solved {
            continue;
        }
        let mut optimal = [false; NC];
        for &i in a.active_set() {
            optimal[usize::from(i)] = true;
        }
        let mut state = crate::qp::Reprobe::<NV, NC>::new(&qp);
        let first = hot.solve_reprobe(&qp, &qp.h, &all, &optimal, 1000, &mut state);
        assert_eq!(first.status, QpStatus::Solved, "qp {k}");
        if first.iterations as usize == first.n_active {
            guessed += 1;
        }
        let h2 = qp.h.map(|v| v - 0.2);
        let second = hot.solve_reprobe(&qp, &h2, &all, &unmarked, 1000, &mut state);
        let fresh = hot.solve_selected(&qp, &h2, &all, &unmarked, 1000);
        assert_eq!(second.status, fresh.status, "qp {k}");
        if fresh.status == QpStatus::Solved {
            let xs = fresh.x.amax().max(1.0);
            assert!((second.x - fresh.x).amax() <= 1e-9 * xs, "qp {k}");
        }
    }
    assert!(guessed > 10, "the guess ended only {guessed} first probes");
}
