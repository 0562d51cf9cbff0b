//! The reference solve: Clarabel (interior point) with a polishing step, and
//! Clarabel as a [`QpBackend`] for whole closed loops.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};
use ldcbf_controller::nalgebra::SVector;
use ldcbf_controller::{DenseQp, DualActiveSet, QpBackend, QpSolution, QpStatus};

use crate::check::kkt_rows;
use crate::problem::DenseProblem;
use crate::stacked::Stacked;

/// Outcome of the reference solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefStatus {
    /// Clarabel `Solved`.
    Solved,
    /// Clarabel `AlmostSolved` (reduced accuracy).
    AlmostSolved,
    /// Clarabel `PrimalInfeasible` or `AlmostPrimalInfeasible`.
    Infeasible,
    /// Anything else (max iterations, numerical error, ...).
    Failed,
}

/// Clarabel's answer.
#[derive(Clone, Debug)]
pub struct RefSolution {
    /// Outcome.
    pub status: RefStatus,
    /// Clarabel's own status, for messages.
    pub raw_status: SolverStatus,
    /// Primal solution.
    pub x: Vec<f64>,
    /// Multipliers of the rows of [`DenseProblem::stacked`] (Clarabel's `z`;
    /// on [`RefStatus::Infeasible`] its certificate of infeasibility).
    pub z: Vec<f64>,
    /// Objective `1/2 x'Px + q'x` recomputed at `x`.
    pub objective: f64,
    /// Clarabel's own primal iterate before polishing (see [`solve_clarabel`]).
    pub x_raw: Vec<f64>,
    /// Whether the polished point replaced the raw iterate.
    pub polished: bool,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Clarabel's measured solve time, s.
    pub solve_time: f64,
}

/// Solves with Clarabel, verbose off, tolerances `1e-12` (gap, feasibility), then
/// *polishes* the answer (as OSQP does): the equality rows and the inequality
/// rows Clarabel reports active (multiplier larger than slack) are taken as
/// equalities and the KKT system `[P A'; A 0] [x; y] = [-q; h_A]` is solved
/// (SVD). The polished point replaces Clarabel's iterate only when it is primal
/// feasible (1e-9), dual feasible (inequality multipliers >= -1e-9) and has
/// smaller KKT residuals.
///
/// The problem is given to Clarabel in the stacked form of
/// [`DenseProblem::stacked`]: the equality rows in a zero cone, the
/// inequality and bound rows in one nonnegative cone; [`RefSolution::z`] comes
/// in that order. A problem that fails [`DenseProblem::validate`] gives
/// [`RefStatus::Failed`] (raw status `NumericalError`) without a solve.
///
/// Why polish: an interior-point method stops at complementarity ~1e-10, which
/// in the flattest direction of `P` can leave the primal iterate 1e-5 away from
/// the optimum while the objective agrees to 1e-13; polishing removes that
/// bias, so the reference stays more accurate than the 1e-6 contract it checks.
/// The raw iterate is kept in [`RefSolution::x_raw`].
pub fn solve_clarabel(p: &DenseProblem) -> RefSolution {
    let n = p.n;
    let st = p.stacked();
    let failed = |raw| RefSolution {
        status: RefStatus::Failed,
        raw_status: raw,
        x_raw: vec![f64::NAN; n],
        polished: false,
        x: vec![f64::NAN; n],
        z: vec![f64::NAN; st.m],
        objective: f64::NAN,
        iterations: 0,
        solve_time: 0.0,
    };
    if p.validate().is_err() {
        return failed(SolverStatus::NumericalError);
    }
    let rows = |mat: &[f64], r: usize| -> Vec<Vec<f64>> {
        (0..r).map(|i| mat[i * n..(i + 1) * n].to_vec()).collect()
    };
    let P = CscMatrix::from(&rows(&p.P, n)).to_triu();
    let A = if st.m == 0 {
        CscMatrix::zeros((0, n))
    } else {
        CscMatrix::from(&rows(&st.G, st.m))
    };
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-12)
        .tol_gap_rel(1e-12)
        .tol_feas(1e-12)
        .tol_infeas_abs(1e-12)
        .tol_infeas_rel(1e-12)
        .tol_ktratio(1e-10)
        .max_iter(200)
        .presolve_enable(false)
        .build()
        .expect("valid Clarabel settings");
    let mut cones = Vec::new();
    if st.me > 0 {
        cones.push(ZeroConeT(st.me));
    }
    if st.m > st.me {
        cones.push(NonnegativeConeT(st.m - st.me));
    }
    let mut solver = match DefaultSolver::new(&P, &p.q, &A, &st.h, &cones, settings) {
        Ok(s) => s,
        Err(_) => return failed(SolverStatus::NumericalError),
    };
    solver.solve();
    let sol = &solver.solution;
    let status = match sol.status {
        SolverStatus::Solved => RefStatus::Solved,
        SolverStatus::AlmostSolved => RefStatus::AlmostSolved,
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            RefStatus::Infeasible
        }
        _ => RefStatus::Failed,
    };
    let mut out = RefSolution {
        status,
        raw_status: sol.status,
        objective: p.objective(&sol.x),
        x: sol.x.clone(),
        x_raw: sol.x.clone(),
        polished: false,
        z: sol.z.clone(),
        iterations: sol.iterations,
        solve_time: sol.solve_time,
    };
    if matches!(status, RefStatus::Solved | RefStatus::AlmostSolved)
        && let Some((x, z)) = polish(p, &st, &sol.x, &sol.z, &sol.s)
    {
        out.objective = p.objective(&x);
        out.x = x;
        out.z = z;
        out.polished = true;
    }
    out
}

/// The polishing step of [`solve_clarabel`] on the stacked rows `st`; `None`
/// when no guessed active set gives a better KKT point. The equality rows are
/// always active; three guesses of the active inequality rows are tried
/// (multiplier > slack, slack ~ 0, multiplier clearly positive), each refined by
/// a few rounds of dropping negative inequality multipliers and adding violated
/// rows; the KKT systems are solved through an SVD so that linearly dependent
/// active rows do not break them.
fn polish(
    p: &DenseProblem,
    st: &Stacked,
    x: &[f64],
    z: &[f64],
    s: &[f64],
) -> Option<(Vec<f64>, Vec<f64>)> {
    let (me, m) = (st.me, st.m);
    let guess = |keep: &dyn Fn(usize) -> bool| -> Vec<usize> {
        (0..me).chain((me..m).filter(|&i| keep(i))).collect()
    };
    let guesses: [Vec<usize>; 3] = [
        guess(&|i| z[i] > s[i]),
        guess(&|i| s[i] <= 1e-8 * (1.0 + st.h[i].abs())),
        guess(&|i| z[i] >= 1e-8),
    ];
    let mut best: Option<(Vec<f64>, Vec<f64>, f64)> = None;
    let base = kkt_rows(p, st, x, z).max();
    for (g, guess) in guesses.iter().enumerate() {
        if guesses[..g].contains(guess) {
            continue; // the same start gives the same point
        }
        // Refine the guess like a primal-dual active-set method: drop the
        // inequality row with the most negative multiplier, else add the most
        // violated row; a few rounds suffice when Clarabel's guess is close.
        let mut active = guess.clone();
        for _ in 0..(2 * p.n + 4) {
            let Some((xp, zp)) = solve_equality_kkt(p, st, &active) else {
                break;
            };
            let neg = active
                .iter()
                .enumerate()
                .filter(|&(_, &i)| i >= me)
                .map(|(r, &i)| (r, zp[i]))
                .filter(|&(_, l)| l < -1e-12)
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((r, _)) = neg {
                active.remove(r);
                continue;
            }
            let viol = (me..m)
                .filter(|i| !active.contains(i))
                .map(|i| (i, st.row_dot(i, &xp) - st.h[i]))
                .filter(|&(_, v)| v > 1e-12)
                .max_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((i, _)) = viol {
                active.push(i);
                continue;
            }
            let k = kkt_rows(p, st, &xp, &zp);
            let score = k.max();
            if k.primal() <= 1e-9
                && k.dual <= 1e-9
                && score < base
                && best.as_ref().is_none_or(|b| score < b.2)
            {
                best = Some((xp, zp, score));
            }
            break;
        }
    }
    best.map(|(xp, mut zp, _)| {
        for v in zp.iter_mut().skip(me) {
            *v = v.max(0.0);
        }
        (xp, zp)
    })
}

/// Solves `[P A'; A 0] [x; y] = [-q; h_A]` for the stacked rows `active` (SVD,
/// so dependent rows get the minimum-norm multipliers).
fn solve_equality_kkt(
    p: &DenseProblem,
    st: &Stacked,
    active: &[usize],
) -> Option<(Vec<f64>, Vec<f64>)> {
    use nalgebra::{DMatrix, DVector};
    let n = p.n;
    let k = active.len();
    let mut kkt_m = DMatrix::<f64>::zeros(n + k, n + k);
    let mut rhs = DVector::<f64>::zeros(n + k);
    for i in 0..n {
        for j in 0..n {
            kkt_m[(i, j)] = p.P[i * n + j];
        }
        rhs[i] = -p.q[i];
    }
    for (r, &i) in active.iter().enumerate() {
        for j in 0..n {
            kkt_m[(n + r, j)] = st.G[i * n + j];
            kkt_m[(j, n + r)] = st.G[i * n + j];
        }
        rhs[n + r] = st.h[i];
    }
    let sol = kkt_m.svd(true, true).solve(&rhs, 1e-13).ok()?;
    if sol.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let xp: Vec<f64> = sol.iter().take(n).copied().collect();
    let mut zp = vec![0.0; st.m];
    for (r, &i) in active.iter().enumerate() {
        zp[i] = sol[n + r];
    }
    Some((xp, zp))
}

/// Clarabel as a [`QpBackend`]: solves each cycle's QP with [`solve_clarabel`]
/// and maps the result into a [`QpSolution`] (active set = rows with slack below
/// 1e-9; multipliers from Clarabel's `z`).
#[derive(Clone, Copy, Debug, Default)]
pub struct ClarabelBackend {
    /// Total Clarabel iterations so far.
    pub iterations: u64,
}

impl<const NV: usize, const NC: usize> QpBackend<NV, NC> for ClarabelBackend {
    fn solve_qp(
        &mut self,
        solver: &DualActiveSet<NV, NC>,
        qp: &DenseQp<NV, NC>,
        _prefer: &[bool; NC],
    ) -> QpSolution<NV, NC> {
        let p = DenseProblem::from_dense_qp(solver.hessian(), qp);
        let r = solve_clarabel(&p);
        self.iterations += u64::from(r.iterations);
        let mut out = QpSolution {
            x: SVector::zeros(),
            lambda: SVector::zeros(),
            objective: f64::NAN,
            status: match r.status {
                RefStatus::Solved | RefStatus::AlmostSolved => QpStatus::Solved,
                RefStatus::Infeasible => QpStatus::Infeasible,
                RefStatus::Failed => QpStatus::NumericalError,
            },
            iterations: r.iterations,
            active: [0; NV].into(),
            n_active: 0,
        };
        if out.status == QpStatus::Infeasible {
            // Clarabel's `z` is then its certificate of primal infeasibility
            // (G'z = 0, h'z < 0): the same meaning as our solver's `lambda`.
            for i in 0..p.m {
                out.lambda[i] = r.z[i].max(0.0);
            }
        }
        if out.status == QpStatus::Solved {
            out.x = SVector::<f64, NV>::from_fn(|i, _| r.x[i]);
            out.objective = r.objective;
            for i in 0..p.m {
                out.lambda[i] = r.z[i].max(0.0);
                let slack = p.h[i] - p.row_dot(i, &r.x);
                if slack.abs() <= 1e-9 && out.n_active < NV {
                    out.active[out.n_active] = i as u16;
                    out.n_active += 1;
                }
            }
        }
        out
    }
}
