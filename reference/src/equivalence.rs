//! The equivalence checks: our dense dual active-set solution of a
//! [`DenseProblem`], its agreement with Clarabel's (SPEC section 3) and the KKT
//! residuals of a primal-dual pair.

use ldcbf_controller::{DualActiveSet, QpSettings, QpSolution, QpStatus};

use crate::clarabel_solve::{RefSolution, RefStatus};
use crate::problem::{DenseProblem, ProblemError};

/// Solves with our dual active-set solver at the fixed size `(NV, NC)`, cold start.
pub fn solve_own<const NV: usize, const NC: usize>(
    p: &DenseProblem,
    max_iter: u32,
) -> Result<QpSolution<NV, NC>, ProblemError> {
    let (H, qp) = p.to_fixed::<NV, NC>()?;
    let solver = DualActiveSet::<NV, NC>::new(&H, QpSettings::default())
        .map_err(|e| ProblemError(format!("Hessian rejected: {e}")))?;
    Ok(solver.solve(&qp, &[false; NC], max_iter))
}

/// The agreement figures of SPEC section 3 for one problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agreement {
    /// `|x_own - x_ref|_inf / (1 + |x_ref|_inf)` (NaN unless both solved).
    pub primal: f64,
    /// `|f_own - f_ref| / max(1, |f_ref|)` (NaN unless both solved).
    pub objective: f64,
    /// Both report feasible, or both infeasible.
    pub feasibility_agrees: bool,
    /// Both solved.
    pub both_solved: bool,
}

impl Agreement {
    /// The contract: feasibility agrees and, when solved, primal <= 1e-6 and
    /// objective <= 1e-8.
    pub fn holds(&self) -> bool {
        self.feasibility_agrees
            && (!self.both_solved || (self.primal <= 1e-6 && self.objective <= 1e-8))
    }
}

/// Compares our solution with Clarabel's on problem `p`.
pub fn compare<const NV: usize, const NC: usize>(
    p: &DenseProblem,
    own: &QpSolution<NV, NC>,
    r: &RefSolution,
) -> Agreement {
    let ref_solved = matches!(r.status, RefStatus::Solved | RefStatus::AlmostSolved);
    let own_solved = own.status == QpStatus::Solved;
    let feasibility_agrees = matches!(
        (own.status, r.status),
        (
            QpStatus::Solved,
            RefStatus::Solved | RefStatus::AlmostSolved
        ) | (QpStatus::Infeasible, RefStatus::Infeasible)
    );
    if !(ref_solved && own_solved) {
        return Agreement {
            primal: f64::NAN,
            objective: f64::NAN,
            feasibility_agrees,
            both_solved: false,
        };
    }
    let xr_norm = r.x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let dx = (0..p.n).fold(0.0f64, |a, i| a.max((own.x[i] - r.x[i]).abs()));
    let fo = p.objective(own.x.as_slice());
    Agreement {
        primal: dx / (1.0 + xr_norm),
        objective: (fo - r.objective).abs() / r.objective.abs().max(1.0),
        feasibility_agrees,
        both_solved: true,
    }
}

/// KKT residuals of a primal-dual pair `(x, lambda)` (all in infinity norm):
/// stationarity `Px + q + G'lambda`, primal `(Gx - h)^+`, dual `(-lambda)^+`,
/// complementarity `max_i |lambda_i (h_i - G_i x)|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kkt {
    /// `|Px + q + G' lambda|_inf`.
    pub stationarity: f64,
    /// `max_i (G_i x - h_i)^+`.
    pub primal: f64,
    /// `max_i (-lambda_i)^+`.
    pub dual: f64,
    /// `max_i |lambda_i (h_i - G_i x)|`.
    pub complementarity: f64,
}

impl Kkt {
    /// Largest of the four residuals.
    pub fn max(&self) -> f64 {
        self.stationarity
            .max(self.primal)
            .max(self.dual)
            .max(self.complementarity)
    }
}

/// Measures the KKT residuals of `(x, lambda)` on `p`.
pub fn kkt(p: &DenseProblem, x: &[f64], lambda: &[f64]) -> Kkt {
    let n = p.n;
    let mut grad: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| p.P[i * n + j] * x[j]).sum::<f64>() + p.q[i])
        .collect();
    let mut primal: f64 = 0.0;
    let mut dual: f64 = 0.0;
    let mut comp: f64 = 0.0;
    for i in 0..p.m {
        let l = lambda[i];
        for (j, g) in grad.iter_mut().enumerate() {
            *g += p.G[i * n + j] * l;
        }
        let slack = p.h[i] - p.row_dot(i, x);
        primal = primal.max(-slack);
        dual = dual.max(-l);
        comp = comp.max((l * slack).abs());
    }
    Kkt {
        stationarity: grad.iter().fold(0.0, |a, g| a.max(g.abs())),
        primal,
        dual,
        complementarity: comp,
    }
}
