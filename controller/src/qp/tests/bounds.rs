//! Simple bounds (`qp/bounds.rs`): which rows are detected, and
//! `solve_bounded` against `solve` on the same rows (bit for bit) and
//! against the bound written as a general row (a scaled unit row, not
//! detected: the same answer to rounding).

use crate::qp::{
    DenseQp, DenseQpOf, DualActiveSet, DualActiveSetOf, QpAllocator, QpSettings, QpSolutionOf,
    QpStatus, SimpleBounds, SimpleBoundsOf,
};
use nalgebra::{Const, DefaultAllocator, Dim, OMatrix, OVector, SMatrix, SVector, U1};
use proptest::prelude::*;

const N: usize = 16;
const C: usize = 48;

fn e(i: usize) -> SVector<f64, N> {
    SVector::from_fn(|k, _| if k == i { 1.0 } else { 0.0 })
}

/// Bit for bit the same answer.
fn same<NV: Dim, NC: Dim>(a: &QpSolutionOf<NV, NC>, b: &QpSolutionOf<NV, NC>) -> bool
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    let bits = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(u, v)| u.to_bits() == v.to_bits());
    a.status == b.status
        && a.iterations == b.iterations
        && a.active_set() == b.active_set()
        && bits(a.x.as_slice(), b.x.as_slice())
        && bits(a.lambda.as_slice(), b.lambda.as_slice())
        && a.objective.to_bits() == b.objective.to_bits()
}

/// A dense positive definite `H`, two general rows, an equality row, and
/// `-1 <= x <= 1` with the minimiser outside the box in a few coordinates.
fn problem(scale: f64) -> (SMatrix<f64, N, N>, DenseQp<N, C>) {
    let a = SMatrix::<f64, N, N>::from_fn(|i, j| ((3 * i + 7 * j) % 11) as f64 / 11.0 - 0.5);
    let h = a * a.transpose() + SMatrix::<f64, N, N>::identity() * 2.0;
    let q = SVector::<f64, N>::from_fn(|i, _| if i % 3 == 0 { -9.0 } else { 0.5 });
    let mut qp = DenseQp::<N, C>::with_q(q);
    qp.push_equality(&(e(2) + e(5)), 0.25).unwrap();
    qp.push_row(&SVector::from_fn(|i, _| (i % 4) as f64 - 1.5), 2.0)
        .unwrap();
    qp.push_row(&(e(0) * 2.0), 1.0).unwrap(); // not a unit row
    for i in 0..N {
        qp.push_row(&(e(i) * scale), scale).unwrap();
        qp.push_row(&(-e(i) * scale), scale).unwrap();
    }
    (h, qp)
}

#[test]
fn detect_finds_the_unit_inequality_rows() {
    let (_, qp) = problem(1.0);
    let b = SimpleBounds::<C>::detect(&qp);
    assert_eq!(b.rows(), 3 + 2 * N);
    assert_eq!(b.count(), 2 * N);
    assert_eq!(b.bound(0), None); // equality row
    assert_eq!(b.bound(1), None); // general row
    assert_eq!(b.bound(2), None); // 2 e_0
    assert_eq!(b.bound(3), Some((0, 1.0)));
    assert_eq!(b.bound(4), Some((0, -1.0)));
    assert_eq!(b.bound(3 + 2 * 7 + 1), Some((7, -1.0)));
    assert_eq!(b.bound(3 + 2 * N), None); // unused row
    let (_, scaled) = problem(2.0);
    assert_eq!(SimpleBounds::<C>::detect(&scaled).count(), 0);
}

#[test]
fn an_active_bound_gives_the_answer_of_the_same_row_and_of_a_general_row() {
    let (h, qp) = problem(1.0);
    let s = DualActiveSet::<N, C>::new(&h, QpSettings::default()).unwrap();
    let bounds = SimpleBounds::<C>::detect(&qp);
    let rows = s.solve(&qp, &[]);
    let bounded = s.solve_bounded(&qp, &bounds, &[]);
    assert_eq!(bounded.status, QpStatus::Solved);
    // Some bound is active, so the bound paths were taken.
    let active_bounds = bounded
        .active_set()
        .iter()
        .filter(|&&a| bounds.bound(usize::from(a)).is_some())
        .count();
    assert!(active_bounds >= 2, "{:?}", bounded.active_set());
    assert!(same(&rows, &bounded));
    // The bounds as the general rows 2 e_j <= 2 (not detected): the same
    // point and multipliers (twice as large per unit of row) to rounding.
    let (_, scaled) = problem(2.0);
    let general = s.solve_bounded(&scaled, &SimpleBounds::<C>::detect(&scaled), &[]);
    assert_eq!(general.status, QpStatus::Solved);
    assert!((general.x - bounded.x).amax() < 1e-12);
    for i in 0..qp.m {
        let w = if i >= 3 { 2.0 } else { 1.0 };
        assert!((general.lambda[i] * w - bounded.lambda[i]).abs() < 1e-9);
    }
}

#[test]
fn bounds_of_another_qp_are_a_numerical_error() {
    let (h, qp) = problem(1.0);
    let s = DualActiveSet::<N, C>::new(&h, QpSettings::default()).unwrap();
    let mut shorter = qp.clone();
    shorter.m -= 1;
    let bounds = SimpleBounds::<C>::detect(&shorter);
    let sol = s.solve_bounded(&qp, &bounds, &[]);
    assert_eq!(sol.status, QpStatus::NumericalError);
}

/// Deterministic numbers in [-1, 1) from a seed (64-bit LCG, top bits).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64) / ((1u64 << 52) as f64) - 1.0
}

/// A random QP with bounds at the sizes `(nv, nc)` (`nc >= me + mg + 2 n`):
/// `mg` general rows, `me` equality rows, each bound finite with
/// probability 3/4 (`lb > ub` on one variable when `crossed`); `H` positive
/// definite, or semidefinite (a zero weight on every third variable) with
/// `semidefinite`.
fn random_qp<NV: Dim, NC: Dim>(
    (nv, nc): (NV, NC),
    seed: u64,
    (mg, me): (usize, usize),
    crossed: bool,
    semidefinite: bool,
) -> (OMatrix<f64, NV, NV>, DenseQpOf<NV, NC>)
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    let n = nv.value();
    let mut st = seed;
    let mut r = || lcg(&mut st);
    let h = if semidefinite {
        OMatrix::<f64, NV, NV>::from_fn_generic(nv, nv, |i, j| {
            if i == j && i % 3 != 0 {
                1.0 + i as f64
            } else {
                0.0
            }
        })
    } else {
        let a = OMatrix::<f64, NV, NV>::from_fn_generic(nv, nv, |_, _| r());
        &a * a.transpose() + OMatrix::<f64, NV, NV>::identity_generic(nv, nv) * 0.1
    };
    let vector =
        |f: &mut dyn FnMut(usize) -> f64| OVector::<f64, NV>::from_fn_generic(nv, U1, |k, _| f(k));
    let q = vector(&mut |_| 4.0 * r());
    let mut qp = DenseQpOf::<NV, NC>::with_q_generic(q, nc);
    for _ in 0..me {
        let g = vector(&mut |_| r());
        qp.push_equality(&g, 0.3 * r()).unwrap();
    }
    for _ in 0..mg {
        let g = vector(&mut |_| r());
        qp.push_row(&g, 0.5 + r()).unwrap();
    }
    for j in 0..n {
        if r() > -0.5 {
            let g = vector(&mut |k| if k == j { 1.0 } else { 0.0 });
            qp.push_row(&g, 0.2 + 0.5 * r()).unwrap();
        }
    }
    for j in 0..n {
        if r() > -0.5 {
            let lb = if crossed && j == n / 2 {
                0.9
            } else {
                -0.2 - 0.5 * r()
            };
            let g = vector(&mut |k| if k == j { -1.0 } else { 0.0 });
            qp.push_row(&g, -lb).unwrap();
        }
    }
    (h, qp)
}

/// `solve_bounded` against `solve` on a random QP of [`random_qp`].
fn check_random<NV: Dim, NC: Dim>(
    dims: (NV, NC),
    seed: u64,
    rows: (usize, usize),
    crossed: bool,
    semidefinite: bool,
) -> Result<(), TestCaseError>
where
    DefaultAllocator: QpAllocator<NV, NC>,
{
    let (h, qp) = random_qp(dims, seed, rows, crossed, semidefinite);
    let s = DualActiveSetOf::<NV, NC>::new(&h, QpSettings::default()).unwrap();
    let bounds = SimpleBoundsOf::detect(&qp);
    prop_assert!(bounds.count() > 0 || qp.m == rows.0 + rows.1);
    let plain = s.solve(&qp, &[]);
    let bounded = s.solve_bounded(&qp, &bounds, &[]);
    prop_assert!(same(&plain, &bounded), "{:?}\n{:?}", plain, bounded);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Random bounded QPs at n = 16 (definite and semidefinite, with and
    /// without equality rows, feasible and crossed bounds): `solve_bounded`
    /// gives `solve`'s answer on the same rows bit for bit, certificates
    /// included.
    #[test]
    fn bounded_solves_equal_the_row_form(
        seed in any::<u64>(),
        mg in 0usize..12,
        me in 0usize..4,
        crossed in any::<bool>(),
        semidefinite in any::<bool>(),
    ) {
        check_random((Const::<16>, Const::<48>), seed, (mg, me), crossed, semidefinite)?;
    }

    /// The same at n = 6, the controller's size (definite `H`, no
    /// equality rows there).
    #[test]
    fn bounded_solves_equal_the_row_form_small(
        seed in any::<u64>(),
        mg in 0usize..12,
        crossed in any::<bool>(),
    ) {
        check_random((Const::<6>, Const::<24>), seed, (mg, 0), crossed, false)?;
    }
}

#[cfg(feature = "alloc")]
proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// The same with run-time sizes, `n` from 2 to 40.
    #[test]
    fn bounded_solves_equal_the_row_form_dyn(
        seed in any::<u64>(),
        n in 2usize..40,
        mg in 0usize..12,
        me in 0usize..4,
        crossed in any::<bool>(),
        semidefinite in any::<bool>(),
    ) {
        let dims = (nalgebra::Dyn(n), nalgebra::Dyn(me.min(n - 1) + mg + 2 * n));
        check_random(dims, seed, (mg, me.min(n - 1)), crossed, semidefinite)?;
    }
}
