//! The dense QP [`DenseProblem`]: built from the controller's assembly or
//! storage types and shaped back into them (the npz layout is in `npz.rs`).

use core::fmt;

use ldcbf_controller::nalgebra::{SMatrix, SVector};
use ldcbf_controller::{Assembly, DenseQp, DualActiveSet};

/// A dense QP `min 1/2 x'Px + q'x  s.t.  Gx <= h` with `n` variables and `m`
/// rows. Matrices are row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct DenseProblem {
    /// Number of variables.
    pub n: usize,
    /// Number of inequality rows.
    pub m: usize,
    /// `P`, `n x n`, row-major, symmetric positive definite.
    pub P: Vec<f64>,
    /// `q`, length `n`.
    pub q: Vec<f64>,
    /// `G`, `m x n`, row-major.
    pub G: Vec<f64>,
    /// `h`, length `m`.
    pub h: Vec<f64>,
}

/// Error reading or shaping a problem.
#[derive(Debug)]
pub struct ProblemError(pub String);

impl fmt::Display for ProblemError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl core::error::Error for ProblemError {}

impl DenseProblem {
    /// The QP of one controller cycle: `P = H` of the solver, `q, G, h` of the
    /// assembly (only the `m` rows in use).
    pub fn from_assembly<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
        solver: &DualActiveSet<NV, NC>,
        asm: &Assembly<N, NV, NC, NOBS>,
    ) -> Self {
        Self::from_dense_qp(solver.hessian(), &asm.qp)
    }

    /// From the controller's storage types.
    pub fn from_dense_qp<const NV: usize, const NC: usize>(
        H: &SMatrix<f64, NV, NV>,
        qp: &DenseQp<NV, NC>,
    ) -> Self {
        let m = qp.m.min(NC);
        let mut P = Vec::with_capacity(NV * NV);
        for i in 0..NV {
            for j in 0..NV {
                P.push(H[(i, j)]);
            }
        }
        let mut G = Vec::with_capacity(m * NV);
        for i in 0..m {
            for j in 0..NV {
                G.push(qp.gt[(j, i)]);
            }
        }
        DenseProblem {
            n: NV,
            m,
            P,
            q: qp.q.iter().copied().collect(),
            G,
            h: qp.h.iter().take(m).copied().collect(),
        }
    }

    /// Objective `1/2 x'Px + q'x`.
    pub fn objective(&self, x: &[f64]) -> f64 {
        let n = self.n;
        let mut f = 0.0;
        for i in 0..n {
            let mut px = 0.0;
            for j in 0..n {
                px += self.P[i * n + j] * x[j];
            }
            f += 0.5 * x[i] * px + self.q[i] * x[i];
        }
        f
    }

    /// Largest row violation `max_i (G_i x - h_i)^+`.
    pub fn max_violation(&self, x: &[f64]) -> f64 {
        (0..self.m)
            .map(|i| self.row_dot(i, x) - self.h[i])
            .fold(0.0, f64::max)
    }

    pub(crate) fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        (0..self.n).map(|j| self.G[i * self.n + j] * x[j]).sum()
    }

    /// Copies the problem into the controller's fixed-size types.
    pub fn to_fixed<const NV: usize, const NC: usize>(
        &self,
    ) -> Result<(SMatrix<f64, NV, NV>, DenseQp<NV, NC>), ProblemError> {
        if self.n != NV || self.m > NC {
            return Err(ProblemError(format!(
                "problem has n = {}, m = {}; the fixed size is NV = {NV}, NC = {NC}",
                self.n, self.m
            )));
        }
        let H = SMatrix::<f64, NV, NV>::from_fn(|i, j| self.P[i * NV + j]);
        let mut qp = DenseQp::<NV, NC> {
            q: SVector::<f64, NV>::from_fn(|i, _| self.q[i]),
            ..DenseQp::default()
        };
        for i in 0..self.m {
            let g = SVector::<f64, NV>::from_fn(|j, _| self.G[i * NV + j]);
            qp.push_row(&g, self.h[i])
                .map_err(|_| ProblemError("row capacity exceeded".into()))?;
        }
        Ok((H, qp))
    }
}
