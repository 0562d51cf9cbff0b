//! Checks on the stacked form of a [`DenseProblem`] (equalities, inequalities
//! and bounds as one row list, see [`Stacked`]): KKT residuals of a primal-dual
//! pair, the Farkas test of an infeasibility certificate, and the agreement of
//! any solver's answer, given as slices, with Clarabel's.

use ldcbf_controller::QpStatus;

use crate::clarabel_solve::{RefSolution, RefStatus};
use crate::problem::{DenseProblem, ProblemError};
use crate::stacked::{RowOrigin, Stacked};

/// KKT residuals of a primal-dual pair `(x, y)` on the stacked form, each in
/// infinity norm (units of the problem's rows, or of its gradient for
/// stationarity).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StackedKkt {
    /// `|Px + q + G_all' y|_inf`.
    pub stationarity: f64,
    /// `max_i |A_i x - b_i|`.
    pub equality: f64,
    /// `max_i (G_i x - h_i)^+`.
    pub inequality: f64,
    /// `max_j max((lb_j - x_j)^+, (x_j - ub_j)^+)` over the finite bounds.
    pub bounds: f64,
    /// `max_i (-y_i)^+` over the inequality and bound rows (equality
    /// multipliers have free sign).
    pub dual: f64,
    /// `max_i |y_i (h_i - g_i x)|` over the inequality and bound rows.
    pub complementarity: f64,
}

impl StackedKkt {
    /// Largest primal residual: equality, inequality or bound.
    pub fn primal(&self) -> f64 {
        nan_max(nan_max(self.equality, self.inequality), self.bounds)
    }

    /// Largest of all residuals (NaN if any is NaN).
    pub fn max(&self) -> f64 {
        [self.primal(), self.dual, self.complementarity]
            .into_iter()
            .fold(self.stationarity, nan_max)
    }
}

/// `max(a, b)` that keeps a NaN (so a NaN residual fails every `<= tol` test).
fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The KKT residuals of `(x, y)` on `p`, `y` the multipliers of the rows of
/// [`DenseProblem::stacked`] (length [`DenseProblem::rows`]). Errors when `x`
/// or `y` has the wrong length.
pub fn kkt_stacked(p: &DenseProblem, x: &[f64], y: &[f64]) -> Result<StackedKkt, ProblemError> {
    let st = p.stacked();
    if x.len() != p.n || y.len() != st.m {
        return Err(ProblemError::KktLengths {
            x: x.len(),
            y: y.len(),
            n: p.n,
            rows: st.m,
        });
    }
    Ok(kkt_rows(p, &st, x, y))
}

/// [`kkt_stacked`] on a precomputed `st = p.stacked()`; entries beyond the
/// ends of `x` and `y` read as NaN.
pub(crate) fn kkt_rows(p: &DenseProblem, st: &Stacked, x: &[f64], y: &[f64]) -> StackedKkt {
    let n = p.n;
    let at = |v: &[f64], k: usize| v.get(k).copied().unwrap_or(f64::NAN);
    let mut grad: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| at(&p.P, i * n + j) * at(x, j)).sum::<f64>() + at(&p.q, i))
        .collect();
    let mut k = StackedKkt {
        stationarity: 0.0,
        equality: 0.0,
        inequality: 0.0,
        bounds: 0.0,
        dual: 0.0,
        complementarity: 0.0,
    };
    for i in 0..st.m {
        let l = at(y, i);
        for (j, g) in grad.iter_mut().enumerate() {
            *g += at(&st.G, i * n + j) * l;
        }
        let slack = at(&st.h, i) - st.row_dot(i, x);
        match st.origin.get(i) {
            Some(RowOrigin::Eq(_)) => {
                k.equality = nan_max(k.equality, slack.abs());
                continue;
            }
            Some(RowOrigin::Ineq(_)) => k.inequality = nan_max(k.inequality, -slack),
            _ => k.bounds = nan_max(k.bounds, -slack),
        }
        k.dual = nan_max(k.dual, -l);
        k.complementarity = nan_max(k.complementarity, (l * slack).abs());
    }
    k.stationarity = grad.iter().fold(0.0, |a, g| nan_max(a, g.abs()));
    k
}

/// How well `y` certifies that the stacked rows have no solution, each figure
/// relative (free of the scales of `y` and of the problem). A certificate
/// `y` with `y_i >= 0` on the inequality rows, `G_all' y = 0` and
/// `h_all' y < 0` proves infeasibility: any feasible `x` would give
/// `0 = y'G_all x <= h_all' y < 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Farkas {
    /// `max_i (-y_i)^+ / |y|_inf` over the inequality rows.
    pub sign: f64,
    /// `|G_all' y|_inf / max_j sum_i |y_i G_ij|`: the residual against the
    /// size of the terms that cancel.
    pub stationarity: f64,
    /// `h_all' y / sum_i |y_i h_i|`, in `[-1, 1]`; negative for a certificate.
    pub objective: f64,
}

impl Farkas {
    /// `sign <= tol`, `stationarity <= tol` and `objective < -tol`.
    pub fn holds(&self, tol: f64) -> bool {
        self.sign <= tol && self.stationarity <= tol && self.objective < -tol
    }
}

/// The [`Farkas`] figures of `y` on `st`; `None` when `y` does not have `st.m`
/// entries, has a non-finite entry or is zero.
pub fn farkas_residuals(st: &Stacked, y: &[f64]) -> Option<Farkas> {
    if y.len() != st.m || st.h.len() != st.m || st.G.len() != st.m.checked_mul(st.n)? {
        return None;
    }
    let ynorm = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if !ynorm.is_finite() || ynorm == 0.0 {
        return None;
    }
    let n = st.n;
    let mut sign: f64 = 0.0;
    let mut gy = vec![0.0; n];
    let mut terms = vec![0.0; n];
    let (mut hy, mut hterms) = (0.0, 0.0);
    for (i, &yi) in y.iter().enumerate() {
        let yi = yi / ynorm;
        if i >= st.me {
            sign = sign.max(-yi);
        }
        for j in 0..n {
            let t = st.G[i * n + j] * yi;
            gy[j] += t;
            terms[j] += t.abs();
        }
        hy += st.h[i] * yi;
        hterms += (st.h[i] * yi).abs();
    }
    let scale = terms.iter().fold(0.0f64, |a, &t| a.max(t));
    let resid = gy.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    Some(Farkas {
        sign,
        stationarity: if scale > 0.0 { resid / scale } else { 0.0 },
        objective: if hterms > 0.0 { hy / hterms } else { 0.0 },
    })
}

/// Whether `y` is a Farkas certificate of infeasibility of `st` to the relative
/// tolerance `tol` (see [`Farkas::holds`]); false when it cannot be measured.
pub fn farkas_holds(st: &Stacked, y: &[f64], tol: f64) -> bool {
    farkas_residuals(st, y).is_some_and(|f| f.holds(tol))
}

/// Tolerance of [`StackedAgreement::holds`]: scaled primal difference, relative
/// objective difference and the [`Farkas`] figures of a certificate.
pub const AGREEMENT_TOL: f64 = 1e-6;

/// Any solver's answer to a [`DenseProblem`], as slices, for
/// [`compare_stacked`].
#[derive(Clone, Copy, Debug)]
pub struct Candidate<'a> {
    /// The solver's verdict.
    pub status: QpStatus,
    /// Primal solution, length `n` (read when solved).
    pub x: &'a [f64],
    /// Multipliers of the stacked rows, length [`DenseProblem::rows`]; on
    /// [`QpStatus::Infeasible`] the Farkas certificate (read then only).
    pub y: &'a [f64],
    /// The objective the solver reports at `x`.
    pub objective: f64,
}

/// Agreement of a [`Candidate`] with Clarabel's [`RefSolution`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StackedAgreement {
    /// `|x - x_ref|_inf` (NaN unless both solved, or `x` has the wrong length).
    pub dx: f64,
    /// `|x_ref|_inf` (NaN unless both solved).
    pub x_ref_norm: f64,
    /// `|f - f_ref| / max(1, |f_ref|)` (NaN unless both solved).
    pub objective: f64,
    /// Both solved, or both report infeasible.
    pub feasibility_agrees: bool,
    /// Both solved.
    pub both_solved: bool,
    /// On the candidate's [`QpStatus::Infeasible`]: whether its `y` passes
    /// [`farkas_holds`] at [`AGREEMENT_TOL`]; `None` otherwise.
    pub certificate: Option<bool>,
}

impl StackedAgreement {
    /// `dx / max(1, |x_ref|_inf)`.
    pub fn primal(&self) -> f64 {
        self.dx / self.x_ref_norm.max(1.0)
    }

    /// The contract: feasibility agrees; when both solved, [`primal`] and
    /// `objective` `<= AGREEMENT_TOL`; a candidate's certificate holds.
    ///
    /// [`primal`]: StackedAgreement::primal
    pub fn holds(&self) -> bool {
        self.feasibility_agrees
            && (!self.both_solved
                || (self.primal() <= AGREEMENT_TOL && self.objective <= AGREEMENT_TOL))
            && self.certificate != Some(false)
    }
}

/// Compares `own` with Clarabel's `r` on `p` (see [`StackedAgreement`]).
pub fn compare_stacked(p: &DenseProblem, own: &Candidate<'_>, r: &RefSolution) -> StackedAgreement {
    let ref_solved = matches!(r.status, RefStatus::Solved | RefStatus::AlmostSolved);
    let own_solved = own.status == QpStatus::Solved;
    let feasibility_agrees = (own_solved && ref_solved)
        || (own.status == QpStatus::Infeasible && r.status == RefStatus::Infeasible);
    let certificate = (own.status == QpStatus::Infeasible)
        .then(|| farkas_holds(&p.stacked(), own.y, AGREEMENT_TOL));
    let mut out = StackedAgreement {
        dx: f64::NAN,
        x_ref_norm: f64::NAN,
        objective: f64::NAN,
        feasibility_agrees,
        both_solved: own_solved && ref_solved,
        certificate,
    };
    if out.both_solved {
        out.x_ref_norm = r.x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if own.x.len() == p.n && r.x.len() == p.n {
            out.dx = own
                .x
                .iter()
                .zip(&r.x)
                .fold(0.0f64, |a, (u, v)| nan_max(a, (u - v).abs()));
        }
        out.objective = (own.objective - r.objective).abs() / r.objective.abs().max(1.0);
    }
    out
}
