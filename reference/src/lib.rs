//! # ldcbf-reference
//!
//! Independent reference for the controller's QP solver: the same QPs, built by
//! the controller's own assembly code, solved by the interior-point solver
//! [Clarabel](https://clarabel.org), and compared with our dense dual
//! active-set solution.
//!
//! * [`DenseProblem`] holds any dense QP `min 1/2 x'Px + q'x  s.t.  Gx <= h`
//!   (row-major), built from a controller [`Assembly`] ([`DenseProblem::from_assembly`])
//!   or read from the npz layout of the external test set ([`DenseProblem::from_npz`]).
//! * [`solve_clarabel`] solves it with Clarabel (verbose off, tight tolerances).
//! * [`solve_own`] solves it with [`DualActiveSet`] at a fixed size.
//! * [`compare`] checks the agreement contract of SPEC section 3; [`kkt`] measures
//!   the KKT residuals of a primal-dual pair.
//! * [`ClarabelBackend`] plugs Clarabel into [`Controller::step_with`] so a whole
//!   closed loop can be run with the reference solver.
//!
//! [`Controller::step_with`]: ldcbf_controller::Controller::step_with
#![allow(non_snake_case)]

use core::fmt;
use std::path::Path;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use ldcbf_controller::nalgebra::{SMatrix, SVector};
use ldcbf_controller::{
    Assembly, DenseQp, DualActiveSet, QpBackend, QpSettings, QpSolution, QpStatus,
};

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

    /// Reads `P, q, G, h` from an `.npz` file of the mpc_qpbenchmark layout (other
    /// keys, pickled `None`s, are ignored): float64 arrays of shapes `[n, n]`,
    /// `[n]`, `[m, n]`, `[m]` (C or Fortran order). Errors name the file and the
    /// key: not a zip archive, a missing key, a truncated or corrupted member
    /// (the zip CRC is checked), another dtype, a wrong shape.
    pub fn from_npz(path: &Path) -> Result<Self, ProblemError> {
        let name = path.display().to_string();
        let fail = |m: String| ProblemError(format!("{name}: {m}"));
        if path.is_dir() {
            return Err(fail("is a directory, not an npz file".into()));
        }
        let mut npz = npyz::npz::NpzArchive::open(path).map_err(|e| {
            fail(match e.kind() {
                std::io::ErrorKind::NotFound => "no such file".into(),
                std::io::ErrorKind::InvalidData => {
                    format!("not an npz file (a zip archive of .npy arrays): {e}")
                }
                _ => format!("cannot open: {e}"),
            })
        })?;
        let mut read = |key: &str| -> Result<(Vec<u64>, Vec<f64>), ProblemError> {
            let bytes =
                read_npz_member(&mut npz, key).map_err(|m| fail(format!("key `{key}`: {m}")))?;
            let (shape, fortran, data) =
                parse_npy_f64(&bytes).map_err(|m| fail(format!("key `{key}`: {m}")))?;
            let data = if fortran && shape.len() == 2 {
                let (r, c) = (shape[0] as usize, shape[1] as usize);
                let mut t = vec![0.0; r * c];
                for i in 0..r {
                    for j in 0..c {
                        t[i * c + j] = data[j * r + i];
                    }
                }
                t
            } else {
                data
            };
            Ok((shape, data))
        };
        let (ps, P) = read("P")?;
        let (qs, q) = read("q")?;
        let (gs, G) = read("G")?;
        let (hs, h) = read("h")?;
        let bad = |key: &str, got: &[u64], want: String| {
            Err(fail(format!(
                "key `{key}` has shape {got:?}, expected {want}"
            )))
        };
        let [n, n2] = ps[..] else {
            return bad("P", &ps, "[n, n]".into());
        };
        if n != n2 {
            return bad("P", &ps, "[n, n]".into());
        }
        if qs[..] != [n] {
            return bad("q", &qs, format!("[{n}] (the size of `P`)"));
        }
        let [m, n3] = gs[..] else {
            return bad("G", &gs, format!("[m, {n}]"));
        };
        if n3 != n {
            return bad("G", &gs, format!("[m, {n}]"));
        }
        if hs[..] != [m] {
            return bad("h", &hs, format!("[{m}] (the rows of `G`)"));
        }
        let (n, m) = (n as usize, m as usize);
        Ok(DenseProblem { n, m, P, q, G, h })
    }

    /// Writes `P, q, G, h` (float64, C order, shapes `[n, n]`, `[n]`, `[m, n]`,
    /// `[m]`) to an `.npz` file, the layout [`DenseProblem::from_npz`] reads and
    /// `numpy.load` opens. (The mpc_qpbenchmark files also carry pickled `None`s
    /// for `A, b, lb, ub`; they are not written.) Errors name the file.
    pub fn write_npz(&self, path: &Path) -> Result<(), ProblemError> {
        use npyz::WriterBuilder;
        let name = path.display().to_string();
        let err = |e: std::io::Error| ProblemError(format!("{name}: cannot write npz: {e}"));
        let mut npz = npyz::npz::NpzWriter::create(path).map_err(err)?;
        let (n, m) = (self.n as u64, self.m as u64);
        let arrays: [(&str, Vec<u64>, &[f64]); 4] = [
            ("P", vec![n, n], &self.P),
            ("q", vec![n], &self.q),
            ("G", vec![m, n], &self.G),
            ("h", vec![m], &self.h),
        ];
        for (key, shape, data) in arrays {
            let mut w = npz
                .array::<f64>(key, Default::default())
                .map_err(err)?
                .default_dtype()
                .shape(&shape)
                .begin_nd()
                .map_err(err)?;
            w.extend(data.iter().copied()).map_err(err)?;
            w.finish().map_err(err)?;
        }
        Ok(())
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

    fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
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
    /// Multipliers of the rows (Clarabel's `z`).
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
/// *polishes* the answer (as OSQP does): the rows Clarabel reports active
/// (multiplier larger than slack) are taken as equalities and the KKT system
/// `[P A'; A 0] [x; y] = [-q; h_A]` is solved by a dense LU with full pivoting. The
/// polished point replaces Clarabel's iterate only when it is primal feasible
/// (1e-9), dual feasible (multipliers >= -1e-9) and has smaller KKT residuals.
///
/// Why: an interior-point method stops at complementarity ~1e-10, which in the
/// flattest direction of `P` can leave the primal iterate 1e-5 away from the
/// optimum while the objective agrees to 1e-13; polishing removes that bias, so
/// the reference stays more accurate than the 1e-6 contract it checks. The raw
/// iterate is kept in [`RefSolution::x_raw`].
pub fn solve_clarabel(p: &DenseProblem) -> RefSolution {
    let n = p.n;
    let rows = |mat: &[f64], r: usize| -> Vec<Vec<f64>> {
        (0..r).map(|i| mat[i * n..(i + 1) * n].to_vec()).collect()
    };
    let P = CscMatrix::from(&rows(&p.P, n)).to_triu();
    let A = if p.m == 0 {
        CscMatrix::zeros((0, n))
    } else {
        CscMatrix::from(&rows(&p.G, p.m))
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
    let cones = [NonnegativeConeT(p.m)];
    let failed = |raw| RefSolution {
        status: RefStatus::Failed,
        raw_status: raw,
        x_raw: vec![f64::NAN; n],
        polished: false,
        x: vec![f64::NAN; n],
        z: vec![f64::NAN; p.m],
        objective: f64::NAN,
        iterations: 0,
        solve_time: 0.0,
    };
    let mut solver = match DefaultSolver::new(&P, &p.q, &A, &p.h, &cones, settings) {
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
        && let Some((x, z)) = polish(p, &sol.x, &sol.z, &sol.s)
    {
        out.objective = p.objective(&x);
        out.x = x;
        out.z = z;
        out.polished = true;
    }
    out
}

/// The polishing step of [`solve_clarabel`]; `None` when no guessed active set
/// gives a better KKT point. Three guesses are tried (multiplier > slack, slack
/// ~ 0, multiplier clearly positive), each refined by a few rounds of dropping
/// negative multipliers and adding violated rows; the KKT systems are solved
/// through an SVD so that linearly dependent active rows do not break them.
fn polish(p: &DenseProblem, x: &[f64], z: &[f64], s: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
    let guesses: [Vec<usize>; 3] = [
        (0..p.m).filter(|&i| z[i] > s[i]).collect(),
        (0..p.m)
            .filter(|&i| s[i] <= 1e-8 * (1.0 + p.h[i].abs()))
            .collect(),
        (0..p.m).filter(|&i| z[i] >= 1e-8).collect(),
    ];
    let mut best: Option<(Vec<f64>, Vec<f64>, f64)> = None;
    let base = kkt(p, x, z).max();
    for guess in &guesses {
        // Refine the guess like a primal-dual active-set method: drop the row with
        // the most negative multiplier, else add the most violated row; a few
        // rounds suffice when Clarabel's guess is close.
        let mut active = guess.clone();
        for _ in 0..(2 * p.n + 4) {
            let Some((xp, zp)) = solve_equality_kkt(p, &active) else {
                break;
            };
            let neg = active
                .iter()
                .enumerate()
                .map(|(r, &i)| (r, zp[i]))
                .filter(|&(_, l)| l < -1e-12)
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((r, _)) = neg {
                active.remove(r);
                continue;
            }
            let viol = (0..p.m)
                .filter(|i| !active.contains(i))
                .map(|i| (i, p.row_dot(i, &xp) - p.h[i]))
                .filter(|&(_, v)| v > 1e-12)
                .max_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((i, _)) = viol {
                active.push(i);
                continue;
            }
            let k = kkt(p, &xp, &zp);
            let score = k.max();
            if k.primal <= 1e-9
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
        for v in zp.iter_mut() {
            *v = v.max(0.0);
        }
        (xp, zp)
    })
}

/// Solves `[P A'; A 0] [x; y] = [-q; h_A]` for the rows `active` (SVD, so
/// dependent rows get the minimum-norm multipliers).
fn solve_equality_kkt(p: &DenseProblem, active: &[usize]) -> Option<(Vec<f64>, Vec<f64>)> {
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
            kkt_m[(n + r, j)] = p.G[i * n + j];
            kkt_m[(j, n + r)] = p.G[i * n + j];
        }
        rhs[n + r] = p.h[i];
    }
    let sol = kkt_m.svd(true, true).solve(&rhs, 1e-13).ok()?;
    if sol.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let xp: Vec<f64> = sol.iter().take(n).copied().collect();
    let mut zp = vec![0.0; p.m];
    for (r, &i) in active.iter().enumerate() {
        zp[i] = sol[n + r];
    }
    Some((xp, zp))
}

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
        _max_iter: u32,
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
            active: SVector::from([0; NV]),
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

/// Largest `.npy` member read from an npz file, bytes (the QPs of this project
/// are a few kB; the cap keeps a corrupt size field from exhausting memory).
const MAX_NPY_BYTES: u64 = 1 << 28;

/// The bytes of `<key>.npy` in `npz`, read to the end so that the zip CRC is
/// checked (a truncated or corrupted member is an error, not wrong numbers).
fn read_npz_member<R: std::io::Read + std::io::Seek>(
    npz: &mut npyz::npz::NpzArchive<R>,
    key: &str,
) -> Result<Vec<u8>, String> {
    use std::io::Read as _;
    if !npz.array_names().any(|n| n == key) {
        return Err("is missing".into());
    }
    let member = npz
        .zip_archive()
        .by_name(&format!("{key}.npy"))
        .map_err(|e| format!("cannot read: {e}"))?;
    if member.size() > MAX_NPY_BYTES {
        return Err(format!(
            "{} bytes, more than the {MAX_NPY_BYTES} read",
            member.size()
        ));
    }
    let mut bytes = Vec::new();
    member
        .take(MAX_NPY_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("truncated or corrupted ({e})"))?;
    Ok(bytes)
}

/// The value text after `'key':` in an `.npy` header dict.
fn npy_header_value<'a>(header: &'a str, key: &str) -> Result<&'a str, String> {
    let at = header
        .find(&format!("'{key}'"))
        .or_else(|| header.find(&format!("\"{key}\"")))
        .ok_or_else(|| format!("the .npy header has no `{key}`"))?;
    let rest = header[at + key.len() + 2..].trim_start();
    rest.strip_prefix(':')
        .map(str::trim_start)
        .ok_or_else(|| format!("malformed .npy header near `{key}`"))
}

/// Parses one `.npy` array of float64 (`<f8` or `>f8`): its shape, whether it
/// is in Fortran order, and the values in file order. Every size is checked
/// against the bytes present, so no header makes this allocate more than the
/// member holds.
fn parse_npy_f64(bytes: &[u8]) -> Result<(Vec<u64>, bool, Vec<f64>), String> {
    let not_npy = || "not an .npy array (no NPY header)".to_string();
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(not_npy());
    }
    let (len, start) = match bytes[6] {
        1 => (
            usize::from(u16::from_le_bytes([bytes[8], bytes[9]])),
            10usize,
        ),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("unsupported .npy format version {v}")),
    };
    let header = bytes
        .get(start..start.saturating_add(len))
        .and_then(|h| core::str::from_utf8(h).ok())
        .ok_or_else(|| "truncated or malformed .npy header".to_string())?;
    let descr = npy_header_value(header, "descr")?;
    let big_endian = if descr.starts_with("'<f8'") || descr.starts_with("\"<f8\"") {
        false
    } else if descr.starts_with("'>f8'") || descr.starts_with("\">f8\"") {
        true
    } else {
        let shown: String = descr.chars().take_while(|&c| c != ',').collect();
        return Err(format!("dtype {shown} is not float64 ('<f8')"));
    };
    let order = npy_header_value(header, "fortran_order")?;
    let fortran = if order.starts_with("True") {
        true
    } else if order.starts_with("False") {
        false
    } else {
        return Err("malformed `fortran_order` in the .npy header".into());
    };
    let shape_text = npy_header_value(header, "shape")?;
    let shape_text = shape_text
        .strip_prefix('(')
        .and_then(|t| t.split_once(')'))
        .map(|(inside, _)| inside)
        .ok_or_else(|| "malformed `shape` in the .npy header".to_string())?;
    let mut shape = Vec::new();
    for d in shape_text
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
    {
        shape.push(
            d.parse::<u64>()
                .map_err(|_| format!("malformed `shape` ({shape_text}) in the .npy header"))?,
        );
    }
    let data = &bytes[start + len..];
    let need = shape
        .iter()
        .try_fold(8u64, |acc, &d| acc.checked_mul(d))
        .filter(|&b| b <= data.len() as u64);
    if need != Some(data.len() as u64) {
        return Err(format!(
            "shape {shape:?} does not match the {} bytes of data (truncated or malformed array)",
            data.len()
        ));
    }
    let values = data
        .chunks_exact(8)
        .map(|c| {
            let mut b = [0u8; 8];
            b.copy_from_slice(c);
            if big_endian {
                f64::from_be_bytes(b)
            } else {
                f64::from_le_bytes(b)
            }
        })
        .collect();
    Ok((shape, fortran, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> DenseProblem {
        // min (x-1)^2 + (y-2)^2  s.t. x + y <= 1
        DenseProblem {
            n: 2,
            m: 1,
            P: vec![2.0, 0.0, 0.0, 2.0],
            q: vec![-2.0, -4.0],
            G: vec![1.0, 1.0],
            h: vec![1.0],
        }
    }

    #[test]
    fn clarabel_and_own_agree_on_a_hand_problem() {
        let p = small();
        let r = solve_clarabel(&p);
        assert_eq!(r.status, RefStatus::Solved);
        assert!((r.x[0] - 0.0).abs() < 1e-8 && (r.x[1] - 1.0).abs() < 1e-8);
        let own = solve_own::<2, 4>(&p, 20).unwrap();
        let a = compare(&p, &own, &r);
        assert!(a.holds(), "{a:?}");
        let k = kkt(&p, own.x.as_slice(), &own.lambda.as_slice()[..p.m]);
        assert!(k.max() < 1e-12, "{k:?}");
    }

    #[test]
    fn infeasible_agreement() {
        let p = DenseProblem {
            n: 2,
            m: 2,
            P: vec![2.0, 0.0, 0.0, 2.0],
            q: vec![0.0, 0.0],
            G: vec![1.0, 0.0, -1.0, 0.0],
            h: vec![-1.0, -1.0],
        };
        let r = solve_clarabel(&p);
        assert_eq!(r.status, RefStatus::Infeasible);
        let own = solve_own::<2, 4>(&p, 20).unwrap();
        assert_eq!(own.status, QpStatus::Infeasible);
        let a = compare(&p, &own, &r);
        assert!(a.feasibility_agrees && !a.both_solved && a.holds());
    }

    #[test]
    fn disagreement_is_detected() {
        let p = small();
        let r = solve_clarabel(&p);
        let mut own = solve_own::<2, 4>(&p, 20).unwrap();
        own.x[0] += 1e-5;
        assert!(!compare(&p, &own, &r).holds());
        own.status = QpStatus::Infeasible;
        assert!(!compare(&p, &own, &r).feasibility_agrees);
    }

    #[test]
    fn npz_round_trip() {
        let p = DenseProblem {
            n: 2,
            m: 3,
            P: vec![2.0, 0.5, 0.5, 1.0],
            q: vec![-1.0, 0.25],
            G: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            h: vec![0.1, 0.2, 0.3],
        };
        let path = std::env::temp_dir().join(format!("ldcbf_ref_{}.npz", std::process::id()));
        p.write_npz(&path).unwrap();
        let back = DenseProblem::from_npz(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(back, p);
    }

    #[test]
    fn npy_headers_are_checked_against_the_data() {
        let npy = |descr: &str, shape: &str, data: &[u8]| {
            let mut h =
                format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
            h.push('\n');
            let mut b = b"\x93NUMPY\x01\x00".to_vec();
            b.extend_from_slice(&(h.len() as u16).to_le_bytes());
            b.extend_from_slice(h.as_bytes());
            b.extend_from_slice(data);
            b
        };
        let two: Vec<u8> = [1.5f64, -2.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let (shape, fortran, v) = parse_npy_f64(&npy("<f8", "(2,)", &two)).unwrap();
        assert_eq!((shape, fortran, v), (vec![2], false, vec![1.5, -2.0]));
        let be: Vec<u8> = [1.5f64, -2.0]
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect();
        assert_eq!(
            parse_npy_f64(&npy(">f8", "(1, 2)", &be)).unwrap().2,
            vec![1.5, -2.0]
        );
        for (b, msg) in [
            (npy("<f8", "(3,)", &two), "does not match the 16 bytes"),
            (npy("<f8", "(1,)", &two), "does not match the 16 bytes"),
            (
                npy("<f8", "(4294967296, 4294967296)", &two),
                "does not match",
            ),
            (npy("<f4", "(4,)", &two), "dtype '<f4' is not float64"),
            (npy("<f8", "(x,)", &two), "malformed `shape`"),
            (
                b"\x93NUMPY\x01\x00\xff\x00{".to_vec(),
                "truncated or malformed .npy header",
            ),
            (b"PK\x03\x04".to_vec(), "not an .npy array"),
        ] {
            let e = parse_npy_f64(&b).unwrap_err();
            assert!(e.contains(msg), "{e}");
        }
    }

    #[test]
    fn wrong_size_is_an_error() {
        assert!(small().to_fixed::<3, 4>().is_err());
        assert!(
            DenseProblem::from_npz(Path::new("/nonexistent.npz"))
                .unwrap_err()
                .0
                .contains("/nonexistent.npz")
        );
    }
}
