//! Deterministic random QPs of every member kind ([`random_problem`]), feasible
//! with a known strictly feasible point or infeasible by construction, for
//! testing solvers against the reference.

use nalgebra::{DMatrix, DVector};

use crate::problem::DenseProblem;

/// What [`random_problem`] builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QpKind {
    /// Feasible: a point `x0` meets every inequality and bound with slack and
    /// every equality exactly.
    Feasible,
    /// Infeasible: two inequality rows `g'x <= h1` and `-c g'x <= -c h2`, with
    /// `h2 > h1` and `c > 0`, at random places among feasible rows (`m` raised
    /// to 2 if smaller).
    OpposedRows,
    /// Infeasible: one equality row `a'x = b` whose `b` lies beyond the range of
    /// `a'x` over the box `lb <= x <= ub` (`me` raised to 1 and `bounds` forced;
    /// the bounds on the row's support made finite).
    EqualityVsBounds,
    /// Infeasible: one equality row a positive combination of one or two
    /// inequality rows, with `b` above the same combination of their `h` (`me`
    /// and `m` raised to 1 if smaller).
    EqualityVsRows,
}

impl QpKind {
    /// True for [`QpKind::Feasible`].
    pub fn is_feasible(self) -> bool {
        self == QpKind::Feasible
    }
}

/// The splitmix64 generator: tiny, fast, and good enough for test data.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        let u = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }

    /// Uniform in `0..k` (`k >= 1`).
    fn below(&mut self, k: usize) -> usize {
        (self.next_u64() % k.max(1) as u64) as usize
    }

    /// True with probability `p`.
    fn chance(&mut self, p: f64) -> bool {
        self.range(0.0, 1.0) < p
    }
}

/// A random dense QP, the same for the same arguments. `n` variables (raised to
/// 1), `m` inequality rows, `me` equality rows, box bounds if `bounds`; `kind`
/// says how it is made infeasible, if at all (and which sizes it raises).
///
/// * `P = Q diag(d) Q'`, `Q` orthogonal (QR of a random matrix), `d`
///   log-spaced over `[1e-2, 1e2]`: condition number `1e4` (for `n >= 2`).
/// * A point `x0` in `[-1, 1]^n`; `q = -P x_u` with the unconstrained
///   minimiser `x_u = x0 + r [-1, 1]^n`, the reach `r` log-uniform in
///   `[0.1, 3.2]`, so that from a few rows to `n` rows are active.
/// * `G` uniform in `[-1, 1]`, `h = G x0 + s`, half the slacks `s` in
///   `[1e-3, 0.1)`, half in `[0.1, 1)`; `A` uniform, `b = A x0`.
/// * Bounds `lb = x0 - [0.05, 1)`, `ub = x0 + [0.05, 1)`, each entry infinite
///   with probability 1/4.
pub fn random_problem(
    seed: u64,
    n: usize,
    m: usize,
    me: usize,
    bounds: bool,
    kind: QpKind,
) -> DenseProblem {
    let n = n.max(1);
    let (m, me, bounds) = match kind {
        QpKind::Feasible => (m, me, bounds),
        QpKind::OpposedRows => (m.max(2), me, bounds),
        QpKind::EqualityVsBounds => (m, me.max(1), true),
        QpKind::EqualityVsRows => (m.max(1), me.max(1), bounds),
    };
    let mut rng = SplitMix64(seed ^ 0x5eed_1dcb_f0a0_0000);
    let uniform = |rng: &mut SplitMix64, k: usize| -> Vec<f64> {
        (0..k).map(|_| rng.range(-1.0, 1.0)).collect::<Vec<_>>()
    };

    // P = Q diag(d) Q', symmetrised.
    let q_mat = DMatrix::from_vec(n, n, uniform(&mut rng, n * n)).qr().q();
    let d = DVector::from_fn(n, |i, _| {
        if n == 1 {
            1.0
        } else {
            10f64.powf(-2.0 + 4.0 * i as f64 / (n - 1) as f64)
        }
    });
    let p_mat = &q_mat * DMatrix::from_diagonal(&d) * q_mat.transpose();
    let P: Vec<f64> = (0..n * n)
        .map(|k| 0.5 * (p_mat[(k / n, k % n)] + p_mat[(k % n, k / n)]))
        .collect();

    let x0 = uniform(&mut rng, n);
    let reach = 10f64.powf(rng.range(-1.0, 0.5));
    let x_u: Vec<f64> = x0
        .iter()
        .map(|v| v + reach * rng.range(-1.0, 1.0))
        .collect();
    let q: Vec<f64> = (0..n)
        .map(|i| -(0..n).map(|j| P[i * n + j] * x_u[j]).sum::<f64>())
        .collect();
    let dot = |row: &[f64], x: &[f64]| row.iter().zip(x).map(|(a, b)| a * b).sum::<f64>();

    let mut G = uniform(&mut rng, m * n);
    let mut h: Vec<f64> = (0..m)
        .map(|i| {
            let s = if rng.chance(0.5) {
                rng.range(1e-3, 0.1)
            } else {
                rng.range(0.1, 1.0)
            };
            dot(&G[i * n..(i + 1) * n], &x0) + s
        })
        .collect();
    let mut A = uniform(&mut rng, me * n);
    let mut b: Vec<f64> = (0..me).map(|i| dot(&A[i * n..(i + 1) * n], &x0)).collect();
    let (mut lb, mut ub) = (Vec::new(), Vec::new());
    if bounds {
        for &x in &x0 {
            let (l, u) = (rng.range(0.05, 1.0), rng.range(0.05, 1.0));
            lb.push(if rng.chance(0.25) {
                f64::NEG_INFINITY
            } else {
                x - l
            });
            ub.push(if rng.chance(0.25) {
                f64::INFINITY
            } else {
                x + u
            });
        }
    }

    match kind {
        QpKind::Feasible => {}
        QpKind::OpposedRows => {
            // g'x <= h1 at row i, g'x >= h2 > h1 (scaled by c) at row k != i.
            let i = rng.below(m);
            let k = (i + 1 + rng.below(m - 1)) % m;
            let g = uniform(&mut rng, n);
            let gnorm = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let h1 = dot(&g, &x0) + rng.range(0.0, 0.5);
            let h2 = h1 + rng.range(0.1, 0.5) * gnorm;
            let c = rng.range(0.2, 5.0);
            for j in 0..n {
                G[i * n + j] = g[j];
                G[k * n + j] = -c * g[j];
            }
            h[i] = h1;
            h[k] = -c * h2;
        }
        QpKind::EqualityVsBounds => {
            // a'x = b with b above max over the box of a'x (finite on a's support).
            let r = rng.below(me);
            let first = rng.below(n);
            let mut a = vec![0.0; n];
            let mut top = 0.0;
            for j in 0..n {
                if j == first || rng.chance(0.5) {
                    a[j] = rng.range(-1.0, 1.0);
                    if !lb[j].is_finite() {
                        lb[j] = x0[j] - rng.range(0.05, 1.0);
                    }
                    if !ub[j].is_finite() {
                        ub[j] = x0[j] + rng.range(0.05, 1.0);
                    }
                    top += if a[j] > 0.0 {
                        a[j] * ub[j]
                    } else {
                        a[j] * lb[j]
                    };
                }
            }
            let anorm = a.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
            A[r * n..(r + 1) * n].copy_from_slice(&a);
            b[r] = top + rng.range(0.1, 1.0) * anorm;
        }
        QpKind::EqualityVsRows => {
            // a = c1 g_i + c2 g_k, b = c1 h_i + c2 h_k + gap: above what the rows allow.
            let r = rng.below(me);
            let i = rng.below(m);
            let k = rng.below(m);
            let (c1, c2) = (rng.range(0.2, 2.0), rng.range(0.0, 2.0));
            let mut a = vec![0.0; n];
            for j in 0..n {
                a[j] = c1 * G[i * n + j] + c2 * G[k * n + j];
            }
            let anorm = a.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
            A[r * n..(r + 1) * n].copy_from_slice(&a);
            b[r] = c1 * h[i] + c2 * h[k] + rng.range(0.1, 1.0) * anorm.max(1e-3);
        }
    }

    DenseProblem {
        n,
        m,
        me,
        P,
        q,
        G,
        h,
        A,
        b,
        lb,
        ub,
    }
}
