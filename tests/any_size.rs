//! The solver at run-time sizes (`DualActiveSetDyn`, feature `alloc` of the
//! controller) against Clarabel on random dense QPs of sizes the controller
//! never compiles: n in {2, 8, 30, 50, 100}, m from n/2 up to 4n, feasible and
//! infeasible ones (inequality rows only; equalities and bounds are not yet
//! handled by the solver, see docs/solvers.md).
//!
//! Checked per problem: the feasibility verdicts agree; when both solve, the
//! primal solutions agree to 1e-6 scaled (`|x - x_ref|_inf / (1 + |x_ref|_inf)`,
//! SPEC section 3); every infeasibility verdict of ours carries a valid Farkas
//! certificate (`y >= 0`, `|G'y|` small against `sum_i y_i |g_i|`, `h'y < 0`).

use ldcbf_controller::nalgebra::{DMatrix, DVector, Dyn};
use ldcbf_controller::{DenseQpDyn, DualActiveSetDyn, QpSettings, QpStatus};
use ldcbf_reference::{DenseProblem, RefStatus, solve_clarabel};

/// Deterministic uniform numbers in [-1, 1) (64-bit LCG, top bits).
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

/// A random QP with `n` variables and `m` rows: `P = A'A + 0.1 I`, rows through
/// a random interior point with positive slack (feasible); for `infeasible`,
/// the last row is a negative combination of three others with a right-hand
/// side below what they allow (so `y` of those four rows certifies it).
fn random_qp(rnd: &mut Rnd, n: usize, m: usize, infeasible: bool) -> DenseProblem {
    let a: Vec<f64> = (0..n * n).map(|_| rnd.next()).collect();
    let mut p = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let s: f64 = (0..n).map(|k| a[k * n + i] * a[k * n + j]).sum();
            p[i * n + j] = s + if i == j { 0.1 } else { 0.0 };
        }
    }
    let q: Vec<f64> = (0..n).map(|_| 5.0 * rnd.next()).collect();
    let x0: Vec<f64> = (0..n).map(|_| 0.5 * rnd.next()).collect();
    let mut g = Vec::with_capacity(m * n);
    let mut h = Vec::with_capacity(m);
    for _ in 0..m {
        let row: Vec<f64> = (0..n).map(|_| rnd.next()).collect();
        let gx: f64 = row.iter().zip(&x0).map(|(a, b)| a * b).sum();
        h.push(gx + 0.05 + 0.5 * rnd.next().abs());
        g.extend(row);
    }
    if infeasible && m >= 4 {
        // g_last = -(g_0 + 2 g_1 + g_2), h_last < -(h_0 + 2 h_1 + h_2).
        let last = m - 1;
        for j in 0..n {
            g[last * n + j] = -(g[j] + 2.0 * g[n + j] + g[2 * n + j]);
        }
        h[last] = -(h[0] + 2.0 * h[1] + h[2]) - 0.1 - rnd.next().abs();
    }
    DenseProblem {
        n,
        m,
        P: p,
        q,
        G: g,
        h,
    }
}

#[test]
fn dynamic_sizes_agree_with_clarabel() {
    let mut rnd = Rnd(0x5eed_0012);
    // (n, problems): fewer at the large sizes (Clarabel in debug builds).
    let sizes = [(2, 12), (8, 12), (30, 6), (50, 4), (100, 2)];
    let (mut solved, mut infeasible) = (0, 0);
    for (n, count) in sizes {
        let mut worst: f64 = 0.0;
        for k in 0..count {
            // m from n / 2 (at least 4) up to 4 n; every third one infeasible.
            let m = (n / 2).max(4) + (k * (4 * n - (n / 2).max(4))) / (count - 1).max(1);
            let p = random_qp(&mut rnd, n, m, k % 3 == 2);
            let solver =
                DualActiveSetDyn::new(&DMatrix::from_row_slice(n, n, &p.P), QpSettings::default())
                    .unwrap();
            let mut qp = DenseQpDyn::with_capacity(DVector::from_column_slice(&p.q), Dyn(m));
            for i in 0..m {
                let g = DVector::from_column_slice(&p.G[i * n..(i + 1) * n]);
                qp.push_row(&g, p.h[i]).unwrap();
            }
            let own = solver.solve(&qp, &[], 10_000);
            let r = solve_clarabel(&p);
            let what = format!(
                "n = {n}, m = {m}, case {k}: ours {:?}, Clarabel {:?}",
                own.status, r.raw_status
            );
            match own.status {
                QpStatus::Solved => {
                    assert!(
                        matches!(r.status, RefStatus::Solved | RefStatus::AlmostSolved),
                        "{what}"
                    );
                    let xr = r.x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                    let dx = (0..n).fold(0.0f64, |a, i| a.max((own.x[i] - r.x[i]).abs()));
                    let primal = dx / (1.0 + xr);
                    assert!(primal <= 1e-6, "{what}: primal {primal:e}");
                    worst = worst.max(primal);
                    solved += 1;
                }
                QpStatus::Infeasible => {
                    assert_eq!(r.status, RefStatus::Infeasible, "{what}");
                    // Farkas certificate: y >= 0, G'y ~ 0, h'y < 0.
                    let y = &own.lambda;
                    let (mut hy, mut scale) = (0.0, 0.0);
                    let mut gy = vec![0.0; n];
                    for i in 0..m {
                        assert!(y[i] >= 0.0, "{what}: y[{i}] = {}", y[i]);
                        let row = &p.G[i * n..(i + 1) * n];
                        for (a, b) in gy.iter_mut().zip(row) {
                            *a += b * y[i];
                        }
                        hy += p.h[i] * y[i];
                        scale += y[i] * row.iter().map(|v| v * v).sum::<f64>().sqrt();
                    }
                    let gy_norm = gy.iter().map(|v| v * v).sum::<f64>().sqrt();
                    assert!(
                        gy_norm <= 1e-9 * scale.max(1.0),
                        "{what}: |G'y| = {gy_norm:e}"
                    );
                    assert!(hy < 0.0, "{what}: h'y = {hy}");
                    infeasible += 1;
                }
                other => panic!("{what}: unexpected status {other:?}"),
            }
        }
        println!("n = {n}: {count} problems, worst scaled primal difference {worst:e}");
    }
    assert!(
        solved >= 20 && infeasible >= 10,
        "{solved} solved, {infeasible} infeasible"
    );
}
