//! The controller's probe state kept from QP to QP (`ReprobeOf::restart`):
//! on hosts with the hot start a solve from scratch sets `J = L^-T` and
//! `R = 0` only when it first reads them (`qp/reprobe.rs`, `Pending`), and
//! zeroes only the columns of `R` an earlier solve may have written. A
//! series of QPs through one restarted state gives, probe for probe, the
//! bits of a state built fresh for each QP, and the columns of `R` past
//! `Pending::r_cols` are zero after every probe.

use super::uniform;
use crate::qp::{DenseQp, DualActiveSet, QpSettings, QpStatus, Reprobe};
use nalgebra::{SMatrix, SVector};

const NV: usize = 16;
const NC: usize = 40;

/// The columns of the state's `R` that `r_cols` says are zero are zero.
fn assert_r_bound(state: &Reprobe<NV, NC>, k: usize, probe: usize) {
    let carry = &state.carry;
    for (j, col) in carry.R.column_iter().enumerate().skip(carry.pending.r_cols) {
        assert!(
            col.iter().all(|&v| v == 0.0),
            "qp {k}, probe {probe}: column {j} of R"
        );
    }
}

#[test]
fn restarted_probes_have_the_bits_of_fresh_ones() {
    let mut rnd = uniform(23);
    let a = SMatrix::<f64, NV, NV>::from_fn(|_, _| rnd());
    let solver = DualActiveSet::<NV, NC>::new(
        &(a.transpose() * a + SMatrix::identity() * 0.1),
        QpSettings::default(),
    )
    .unwrap();
    let enabled = [true; NC];
    let unmarked = [false; NC];
    let mut state = Reprobe::<NV, NC>::EMPTY;
    // Probes a guess ended (the factor left unset), that stepped, and that
    // ended at the unconstrained minimiser without a step.
    let (mut guessed, mut stepped, mut no_step) = (0, 0, 0);
    for k in 0..150 {
        let mut qp = DenseQp::<NV, NC>::with_q(SVector::from_fn(|_, _| 5.0 * rnd()));
        // Every seventh QP: right-hand sides the unconstrained minimiser
        // meets.
        let lift = if k % 7 == 0 { 1e3 } else { 0.3 };
        for _ in 0..NC {
            let g = SVector::<f64, NV>::from_fn(|_, _| rnd());
            let _ = qp.push_row(&g, rnd() + lift);
        }
        // Marks: none, the optimal active set, or that with wrong rows.
        let mut marks = [false; NC];
        if k % 3 != 0 {
            let cold = solver.solve(&qp, &unmarked);
            for &i in cold.active_set() {
                marks[usize::from(i)] = true;
            }
            if k % 3 == 2 {
                for m in marks.iter_mut().step_by(5) {
                    *m = true;
                }
            }
        }
        state.restart(&solver, &qp);
        let mut fresh = Reprobe::for_solver(&solver, &qp);
        for probe in 0..3 {
            let h = qp.h.map(|v| v - 0.15 * probe as f64);
            let prefer = if probe == 0 { &marks } else { &unmarked };
            let got = solver.solve_reprobe(&qp, &h, &enabled, prefer, 1000, &mut state);
            let want = solver.solve_reprobe(&qp, &h, &enabled, prefer, 1000, &mut fresh);
            assert_eq!(got.status, want.status, "qp {k}, probe {probe}");
            assert_eq!(got.iterations, want.iterations, "qp {k}, probe {probe}");
            assert_eq!(got.active_set(), want.active_set(), "qp {k}, probe {probe}");
            for (x, y) in got.x.iter().zip(want.x.iter()) {
                assert_eq!(x.to_bits(), y.to_bits(), "qp {k}, probe {probe}");
            }
            for (x, y) in got.lambda.iter().zip(want.lambda.iter()) {
                assert_eq!(x.to_bits(), y.to_bits(), "qp {k}, probe {probe}");
            }
            assert_r_bound(&state, k, probe);
            if state.carry.pending.unset {
                guessed += 1;
            } else if got.status == QpStatus::Solved && got.iterations == 0 {
                no_step += 1;
            } else {
                stepped += 1;
            }
        }
    }
    assert!(guessed > 20, "{guessed} probes a guess ended");
    assert!(stepped > 100, "{stepped} probes that stepped");
    assert!(no_step > 10, "{no_step} probes without a step");
}
