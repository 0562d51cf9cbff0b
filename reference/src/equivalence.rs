//! The equivalence checks: our dense dual active-set solution of a
//! [`DenseProblem`], its agreement with Clarabel's (docs/maths.md §3) and the KKT
//! residuals of a primal-dual pair.

use ldcbf_controller::{
    DualActiveSet, DualActiveSetDyn, QpSettings, QpSolution, QpSolutionDyn, SimpleBoundsDyn,
};

use crate::check::{Candidate, compare_stacked, kkt_rows};
use crate::clarabel_solve::RefSolution;
use crate::problem::{DenseProblem, ProblemError};

// Named in the docs only (intra-doc links).
#[cfg(doc)]
use crate::check::kkt_stacked;

/// Solves with our dual active-set solver at the fixed size `(NV, NC)`, cold start.
pub fn solve_own<const NV: usize, const NC: usize>(
    p: &DenseProblem,
    max_iter: u32,
) -> Result<QpSolution<NV, NC>, ProblemError> {
    let (H, qp) = p.to_fixed::<NV, NC>()?;
    let solver =
        DualActiveSet::<NV, NC>::new(&H, settings(max_iter)).map_err(ProblemError::Hessian)?;
    Ok(solver.solve(&qp, &[false; NC]))
}

/// Solves with the run-time-sized instance of our solver (any `n`, any
/// number of rows, equality rows held as equalities, the bound rows of `lb`
/// and `ub` as simple bounds: `solve_bounded`), cold start.
pub fn solve_own_dyn(p: &DenseProblem, max_iter: u32) -> Result<QpSolutionDyn, ProblemError> {
    let (H, qp) = p.to_dyn()?;
    let solver = DualActiveSetDyn::new(&H, settings(max_iter)).map_err(ProblemError::Hessian)?;
    let bounds = SimpleBoundsDyn::detect(&qp);
    Ok(solver.solve_bounded(&qp, &bounds, &[]))
}

/// The default settings with the iteration limit `max_iter`.
fn settings(max_iter: u32) -> QpSettings {
    QpSettings {
        max_iter,
        ..QpSettings::default()
    }
}

/// The agreement figures of docs/maths.md §3 for one problem.
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

/// Compares our solution with Clarabel's on problem `p`: [`compare_stacked`]
/// with the objective recomputed at our `x`, its figures in the docs/maths.md §3
/// scaling.
pub fn compare<const NV: usize, const NC: usize>(
    p: &DenseProblem,
    own: &QpSolution<NV, NC>,
    r: &RefSolution,
) -> Agreement {
    let rows = p.rows().min(NC);
    let own = Candidate {
        status: own.status,
        x: own.x.as_slice(),
        y: &own.lambda.as_slice()[..rows],
        objective: p.objective(own.x.as_slice()),
    };
    let a = compare_stacked(p, &own, r);
    Agreement {
        primal: a.dx / (1.0 + a.x_ref_norm),
        objective: a.objective,
        feasibility_agrees: a.feasibility_agrees,
        both_solved: a.both_solved,
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

/// Measures the KKT residuals of `(x, lambda)` on `p`: [`kkt_stacked`] with the
/// primal residuals in one figure; `lambda` holds the multipliers of the
/// stacked rows (extra entries are ignored). Slices too short give NaN
/// residuals.
pub fn kkt(p: &DenseProblem, x: &[f64], lambda: &[f64]) -> Kkt {
    let st = p.stacked();
    let k = kkt_rows(p, &st, x, lambda.get(..st.m).unwrap_or(&[]));
    Kkt {
        stationarity: k.stationarity,
        primal: k.primal(),
        dual: k.dual,
        complementarity: k.complementarity,
    }
}
