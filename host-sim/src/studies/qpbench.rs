//! `ldcbf-sim qp solve`: our dual active-set solver on dense QPs stored in the
//! npz layout of qpbenchmark (`tests/data/lipmwalk/`): `P, q, G, h, A, b, lb, ub`
//! for `min 1/2 x'Px + q'x  s.t.  Gx <= h, Ax = b, lb <= x <= ub`, any of the
//! last six absent or empty, timed so that anyone can compare it with other
//! solvers on identical problems (`run --export-qps DIR` writes every cycle's
//! QP of a simulation in the same layout). The solver takes the stacked rows
//! of [`DenseProblem::stacked`]: the equality rows `A, b` first, held as
//! equalities (never dropped, multipliers of either sign), then `G, h`, then
//! the finite bounds as rows (the CSV's `m` counts all of them).
//!
//! One algorithm at every size: a file is solved by the static instance
//! `(NV, NC)` of the solver when one is compiled with `NV = n` and `NC >= m`
//! (see [`SIZES`]; for equality rows only from `NV = 16` on, where they are
//! compiled in), and by the run-time-sized instance (`Dyn`) otherwise; the
//! CSV's `path` column says which (`static` or `dynamic`). Both are the same
//! code and give bit-identical results where both apply. The Hessian is
//! factored once per file, outside the timing, as the controller does once per
//! configuration. Five times are reported, each the minimum over `repeat`
//! calls (cold start), in nanoseconds:
//!
//! * `min_solve_ns`: [`DualActiveSetOf::solve`], which starts from the raw rows
//!   of `G` (row norms included), as the controller's cycle does (its `G`
//!   changes every cycle);
//! * `min_prepared_ns`: [`DualActiveSetOf::solve_prepared`] with the row norms
//!   of [`DualActiveSetOf::prepare_rows`] computed outside the timing: the
//!   figure for a QP family whose `G` is fixed and only `q`, `h` change
//!   (LIPMWALK);
//! * `min_ldp_ns`: [`LdpSolverOf::solve`], the range-space (least-distance)
//!   path for a fixed `G`, with [`LdpSolverOf::prepare`] (per `G`) and
//!   [`LdpSolverOf::load`] (per `q`, `h`: `v = L^-1 q` and the slacks at the
//!   unconstrained minimiser) outside the timing: the same split as DAQP's
//!   `setup_time` / `solve_time` (with equality rows it solves by the
//!   orthogonal factor, as `solve_prepared`);
//! * `min_ldp_load_ns`: [`LdpSolverOf::load`] alone, so that
//!   `min_ldp_ns + min_ldp_load_ns` is the per-`(q, h)` cost;
//! * `min_ldp_prepare_ns`: [`LdpSolverOf::prepare`] alone (per `G`; what a
//!   controller whose `G` changes every cycle would pay on top).
//!
//! Both other paths are checked against `solve` before timing (an error
//! otherwise): `solve_prepared` bit for bit; the LDP path for the same status,
//! the objective to 1e-9 relative (`|a - b| <= 1e-9 max(1, |a|, |b|)`) and `x`
//! to 1e-9 scaled (`max |x_a - x_b| <= 1e-9 max(1, max |x|)`). With `check`,
//! every file is also solved by Clarabel and the answer checked with
//! [`compare_stacked`] (primal to 1e-6 scaled, objective to 1e-6, the same
//! feasibility verdict, a valid Farkas certificate when infeasible); the
//! figures go to the columns `clarabel_dx` (scaled primal difference) and
//! `clarabel_dobj`, and a disagreement is an error naming the file.

use std::path::{Path, PathBuf};
use std::time::Instant;

use ldcbf_controller::nalgebra::{Const, DefaultAllocator, Dim, Dyn};
use ldcbf_controller::{
    DenseQpOf, DualActiveSetOf, HessianError, LdpSolverOf, QpAllocator, QpSettings, QpSolutionOf,
    QpStatus, SimpleBoundsOf,
};
use ldcbf_reference::{Candidate, DenseProblem, ProblemError, compare_stacked, solve_clarabel};

/// Why a QP file could not be solved and checked, or the options are out of
/// range; each names the file (and the field where there is one).
#[derive(Debug, thiserror::Error)]
pub enum QpBenchError {
    /// `--repeat` outside `1..=MAX_REPEAT`.
    #[error("--repeat must be in 1..={MAX_REPEAT}, got {0}")]
    Repeat(usize),
    /// `--max-iter 0`.
    #[error("--max-iter must be >= 1, got 0")]
    MaxIter,
    /// The file could not be read as a problem (the message names the file).
    #[error(transparent)]
    Read(ProblemError),
    /// The problem does not fit the solver's sizes.
    #[error("{}: {error}", file.display())]
    Problem {
        /// The file.
        file: PathBuf,
        /// Why.
        error: ProblemError,
    },
    /// The Hessian (field `P`) was refused by the solver.
    #[error("{}: field `P`: {error}", file.display())]
    Hessian {
        /// The file.
        file: PathBuf,
        /// Why.
        error: HessianError,
    },
    /// `solve` and `solve_prepared` disagree (status, iterations or `x`).
    #[error("{}: solve and solve_prepared disagree ({solve:?} vs {prepared:?})", file.display())]
    Prepared {
        /// The file.
        file: PathBuf,
        /// `solve`'s status.
        solve: QpStatus,
        /// `solve_prepared`'s status.
        prepared: QpStatus,
    },
    /// `solve` and `solve_bounded` (the unit rows as simple bounds) do not
    /// give the same answer bit for bit.
    #[error("{}: solve and solve_bounded disagree ({solve:?} vs {bounded:?})", file.display())]
    Bounded {
        /// The file.
        file: PathBuf,
        /// `solve`'s status.
        solve: QpStatus,
        /// `solve_bounded`'s status.
        bounded: QpStatus,
    },
    /// `solve` and the LDP solve disagree on the status.
    #[error(
        "{}: solve and the LDP solve disagree on the status ({solve:?} vs {ldp:?})",
        file.display()
    )]
    LdpStatus {
        /// The file.
        file: PathBuf,
        /// `solve`'s status.
        solve: QpStatus,
        /// The LDP solve's status.
        ldp: QpStatus,
    },
    /// `solve` and the LDP solve disagree on the objective or `x`.
    #[error(
        "{}: solve and the LDP solve disagree (objective {solve} vs {ldp}, scaled x difference {dx:e})",
        file.display()
    )]
    Ldp {
        /// The file.
        file: PathBuf,
        /// `solve`'s objective.
        solve: f64,
        /// The LDP solve's objective.
        ldp: f64,
        /// `max |x_a - x_b| / max(1, max |x|)`.
        dx: f64,
    },
    /// Our solution and Clarabel's disagree (module docs).
    #[error(
        "{}: our solution and Clarabel's disagree (ours {ours:?}, Clarabel {clarabel}; scaled \
         primal difference {dx:e}, objective {objective:e}, certificate {certificate:?})",
        file.display()
    )]
    Clarabel {
        /// The file.
        file: PathBuf,
        /// Our status.
        ours: QpStatus,
        /// Clarabel's raw status (its `Debug` form).
        clarabel: String,
        /// Scaled primal difference.
        dx: f64,
        /// Relative objective difference.
        objective: f64,
        /// Whether our Farkas certificate holds (on infeasible).
        certificate: Option<bool>,
    },
}

/// `Result` of this module.
type Result<T, E = QpBenchError> = core::result::Result<T, E>;

/// The compiled solver sizes `(NV, NC)`, listed once: `with_qp_sizes!(m)`
/// expands to `m!((6, 48), (6, 72), ...)`. It defines [`SIZES`], the dispatch
/// in [`solve_file`] and the Python package's `solve_qp`.
#[macro_export]
macro_rules! with_qp_sizes {
    ($m:ident) => {
        $m!(
            (6, 48),
            (6, 72),
            (6, 120),
            (10, 80),
            (16, 32),
            (16, 128),
            (20, 160)
        )
    };
}

macro_rules! size_list {
    ($(($nv:literal, $nc:literal)),*) => { [$(($nv, $nc)),*] };
}

/// The static instances `(n, max m)`: the controller's configurations (N = 3
/// with 8 or 16 obstacles and with foot clearance, N = 5, N = 10) and the
/// external LIPMWALK set. Any other size is solved by the `Dyn` instance.
pub const SIZES: [(usize, usize); 7] = with_qp_sizes!(size_list);

/// One file's result.
#[derive(Clone, Debug, PartialEq)]
pub struct QpRow {
    /// The file.
    pub file: PathBuf,
    /// Variables.
    pub n: usize,
    /// Rows.
    pub m: usize,
    /// Solver status.
    pub status: QpStatus,
    /// Adds plus drops.
    pub iterations: u32,
    /// Objective `1/2 x'Px + q'x` (NaN unless solved).
    pub objective: f64,
    /// Minimum solve time over the repeats, ns.
    pub min_ns: u64,
    /// Minimum time of the solve with prepared row norms over the repeats, ns.
    pub min_prepared_ns: u64,
    /// Minimum time of the LDP solve (prepare and load outside), ns.
    pub min_ldp_ns: u64,
    /// Minimum time of the LDP load alone, ns.
    pub min_ldp_load_ns: u64,
    /// Minimum time of the LDP prepare alone, ns.
    pub min_ldp_prepare_ns: u64,
    /// Adds plus drops of the LDP solve.
    pub ldp_iterations: u32,
    /// Which instance solved it: `static` (compiled size) or `dynamic`.
    pub path: &'static str,
    /// With `check`: Clarabel's agreement, `(|x - x_ref|_inf / max(1,
    /// |x_ref|_inf), |f - f_ref| / max(1, |f_ref|))` (NaN unless both solved).
    pub clarabel: Option<(f64, f64)>,
}

/// The CSV header of [`QpRow::csv`].
pub const CSV_HEADER: &str = "file,n,m,status,iterations,objective,min_solve_ns,min_prepared_ns,min_ldp_ns,min_ldp_load_ns,ldp_iterations,min_ldp_prepare_ns,path,clarabel_dx,clarabel_dobj";

impl QpRow {
    /// One CSV line (no newline).
    pub fn csv(&self) -> String {
        let status = self.status.name();
        let (dx, dobj) = match self.clarabel {
            Some((dx, dobj)) => (format!("{dx:.3e}"), format!("{dobj:.3e}")),
            None => (String::new(), String::new()),
        };
        format!(
            "{},{},{},{},{},{:.17e},{},{},{},{},{},{},{},{dx},{dobj}",
            self.file.display(),
            self.n,
            self.m,
            status,
            self.iterations,
            self.objective,
            self.min_ns,
            self.min_prepared_ns,
            self.min_ldp_ns,
            self.min_ldp_load_ns,
            self.ldp_iterations,
            self.min_ldp_prepare_ns,
            self.path
        )
    }
}

/// The same answer bit for bit: status, iterations, active set, `x`,
/// multipliers (or certificate) and objective.
fn same_answer<V: Dim, C: Dim>(a: &QpSolutionOf<V, C>, b: &QpSolutionOf<V, C>) -> bool
where
    DefaultAllocator: QpAllocator<V, C>,
{
    let bits = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(u, v)| u.to_bits() == v.to_bits());
    a.status == b.status
        && a.iterations == b.iterations
        && a.active_set() == b.active_set()
        && bits(a.x.as_slice(), b.x.as_slice())
        && bits(a.lambda.as_slice(), b.lambda.as_slice())
        && a.objective.to_bits() == b.objective.to_bits()
}

/// Solves and times one file with the instance of dimensions `(nv, nc)`
/// (static or dynamic: the same code).
fn solve_sized<V: Dim, C: Dim>(
    file: &Path,
    p: &DenseProblem,
    (nv, nc): (V, C),
    opts: &SolveOptions,
    path: &'static str,
) -> Result<QpRow>
where
    DefaultAllocator: QpAllocator<V, C>,
{
    let repeat = opts.repeat;
    let (h, qp) = p.to_qp(nv, nc).map_err(|error| QpBenchError::Problem {
        file: file.to_path_buf(),
        error,
    })?;
    let settings = QpSettings {
        max_iter: opts.max_iter,
        ..QpSettings::default()
    };
    let solver =
        DualActiveSetOf::<V, C>::new(&h, settings).map_err(|error| QpBenchError::Hessian {
            file: file.to_path_buf(),
            error,
        })?;
    let prefer: &[bool] = &[];
    let rows = solver.prepare_rows(&qp);
    // The bound rows (`lb`, `ub`), known from the format, found once per
    // G (outside the timing): with any, the timed `solve` is
    // `solve_bounded`, checked against `solve` bit for bit first.
    let bounds = SimpleBoundsOf::detect(&qp);
    let timed = |qp: &DenseQpOf<V, C>| {
        if bounds.count() > 0 {
            solver.solve_bounded(qp, &bounds, prefer)
        } else {
            solver.solve(qp, prefer)
        }
    };
    let (mut best, mut best_prepared) = (u64::MAX, u64::MAX);
    let (mut best_ldp, mut best_load, mut best_prep) = (u64::MAX, u64::MAX, u64::MAX);
    let mut sol = solver.solve(&qp, prefer);
    let prepared = solver.solve_prepared(&qp, &rows, prefer);
    let same_x = prepared
        .x
        .iter()
        .zip(sol.x.iter())
        .all(|(a, b)| a.to_bits() == b.to_bits());
    if prepared.status != sol.status || prepared.iterations != sol.iterations || !same_x {
        return Err(QpBenchError::Prepared {
            file: file.to_path_buf(),
            solve: sol.status,
            prepared: prepared.status,
        });
    }
    let bounded = timed(&qp);
    if !same_answer(&sol, &bounded) {
        return Err(QpBenchError::Bounded {
            file: file.to_path_buf(),
            solve: sol.status,
            bounded: bounded.status,
        });
    }
    // The LDP path: `ldp` per G, `loaded` per (q, h), both outside the timing.
    let ldp = Box::new(LdpSolverOf::prepare(&solver, &qp));
    let loaded = ldp.load(&qp.q, &qp.h);
    let lsol = ldp.solve(&loaded, prefer);
    check_ldp(file, &sol, &lsol)?;
    let ns = |t0: Instant| u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX);
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        sol = std::hint::black_box(timed(std::hint::black_box(&qp)));
        best = best.min(ns(t0));
        let t0 = Instant::now();
        std::hint::black_box(solver.solve_prepared(std::hint::black_box(&qp), &rows, prefer));
        best_prepared = best_prepared.min(ns(t0));
        let t0 = Instant::now();
        std::hint::black_box(ldp.solve(std::hint::black_box(&loaded), prefer));
        best_ldp = best_ldp.min(ns(t0));
        let t0 = Instant::now();
        std::hint::black_box(ldp.load(std::hint::black_box(&qp.q), &qp.h));
        best_load = best_load.min(ns(t0));
        let t0 = Instant::now();
        let prepared = LdpSolverOf::prepare(&solver, std::hint::black_box(&qp));
        best_prep = best_prep.min(ns(t0));
        std::hint::black_box(&prepared);
    }
    let clarabel = if opts.check {
        Some(check_clarabel(file, p, &sol)?)
    } else {
        None
    };
    Ok(QpRow {
        file: file.to_path_buf(),
        n: p.n,
        m: p.rows(),
        status: sol.status,
        iterations: sol.iterations,
        objective: if sol.status.is_solved() {
            sol.objective
        } else {
            f64::NAN
        },
        min_ns: best,
        min_prepared_ns: best_prepared,
        min_ldp_ns: best_ldp,
        min_ldp_load_ns: best_load,
        ldp_iterations: lsol.iterations,
        min_ldp_prepare_ns: best_prep,
        path,
        clarabel,
    })
}

/// The LDP solution `b` agrees with `solve`'s `a`: same status; when solved,
/// objective to 1e-9 relative and `x` to 1e-9 scaled.
fn check_ldp<V: Dim, C: Dim>(
    file: &Path,
    a: &QpSolutionOf<V, C>,
    b: &QpSolutionOf<V, C>,
) -> Result<()>
where
    DefaultAllocator: QpAllocator<V, C>,
{
    if a.status != b.status {
        return Err(QpBenchError::LdpStatus {
            file: file.to_path_buf(),
            solve: a.status,
            ldp: b.status,
        });
    }
    if a.status.is_solved() {
        let (oa, ob) = (a.objective, b.objective);
        let dobj = (oa - ob).abs() / oa.abs().max(ob.abs()).max(1.0);
        let dx = (&a.x - &b.x).amax() / a.x.amax().max(1.0);
        if !(dobj <= 1e-9 && dx <= 1e-9) {
            return Err(QpBenchError::Ldp {
                file: file.to_path_buf(),
                solve: oa,
                ldp: ob,
                dx,
            });
        }
    }
    Ok(())
}

/// Clarabel's agreement with our solution `sol` of `p` (module docs): an
/// error naming the file when it does not hold.
fn check_clarabel<V: Dim, C: Dim>(
    file: &Path,
    p: &DenseProblem,
    sol: &QpSolutionOf<V, C>,
) -> Result<(f64, f64)>
where
    DefaultAllocator: QpAllocator<V, C>,
{
    let r = solve_clarabel(p);
    let y = sol.lambda.as_slice().get(..p.rows()).unwrap_or(&[]);
    let own = Candidate {
        status: sol.status,
        x: sol.x.as_slice(),
        y,
        objective: sol.objective,
    };
    let a = compare_stacked(p, &own, &r);
    if !a.holds() {
        return Err(QpBenchError::Clarabel {
            file: file.to_path_buf(),
            ours: sol.status,
            clarabel: format!("{:?}", r.raw_status),
            dx: a.dx / a.x_ref_norm.max(1.0),
            objective: a.objective,
            certificate: a.certificate,
        });
    }
    Ok((a.dx / a.x_ref_norm.max(1.0), a.objective))
}

/// What `qp solve` does with each file.
#[derive(Clone, Copy, Debug)]
pub struct SolveOptions {
    /// Timed repeats per file (the minimum is reported).
    pub repeat: usize,
    /// Iteration budget per solve.
    pub max_iter: u32,
    /// Also solve with Clarabel and check the agreement.
    pub check: bool,
}

/// Most timed repeats per file ([`SolveOptions::repeat`]).
pub const MAX_REPEAT: usize = 1_000_000;

impl SolveOptions {
    /// Checks the limits: `repeat` in `1..=MAX_REPEAT`, `max_iter >= 1` (as
    /// the controller's `Config::max_iter`).
    pub fn validate(&self) -> Result<()> {
        if !(1..=MAX_REPEAT).contains(&self.repeat) {
            return Err(QpBenchError::Repeat(self.repeat));
        }
        if self.max_iter == 0 {
            return Err(QpBenchError::MaxIter);
        }
        Ok(())
    }
}

/// Reads and solves one file (see the module docs), after
/// [`SolveOptions::validate`].
pub fn solve_file(file: &Path, opts: &SolveOptions) -> Result<QpRow> {
    opts.validate()?;
    use crate::scenario::limits::{MAX_TABLE_BYTES, check_regular_file};
    if let Err(e) = check_regular_file(file, MAX_TABLE_BYTES)
        && e.kind() != std::io::ErrorKind::NotFound
    {
        return Err(QpBenchError::Read(ProblemError::File {
            file: file.display().to_string(),
            reason: e.to_string(),
        }));
    }
    let p = DenseProblem::from_npz(file).map_err(QpBenchError::Read)?;
    // The solver's rows: `A` (equalities), `G` and the finite bounds.
    let rows = p.rows();
    macro_rules! dispatch {
        ($(($nv:literal, $nc:literal)),*) => {
            $(if p.n == $nv && rows <= $nc && (p.me == 0 || $nv >= ldcbf_controller::qp::HOT_START_MIN_NV) {
                return solve_sized(file, &p, (Const::<$nv>, Const::<$nc>), opts, "static");
            })*
        };
    }
    with_qp_sizes!(dispatch);
    solve_sized(file, &p, (Dyn(p.n), Dyn(rows)), opts, "dynamic")
}
