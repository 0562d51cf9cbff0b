//! The QP solver in qpsolvers' problem form, numpy buffers read in place:
//! [`solve_dense`] (one cold solve) and [`PyQpSolver`] (`QpSolver`: `P`
//! factored once, repeated solves that reuse the factor, the row storage and
//! the previous active set).
//!
//! `min 1/2 x'Px + q'x  s.t.  Gx <= h, Ax = b, lb <= x <= ub`. The members
//! are borrowed as a [`ProblemView`] (no per-element conversion: a C-contiguous
//! float64 array is read where it lies; anything else is converted once by
//! numpy) and written straight into the solver's storage at a compiled size
//! when `n` and the stacked rows fit one (`QP_SIZES`), else into the
//! run-time-sized instance (the same code).

use ldcbf_controller::nalgebra::{Const, DefaultAllocator, Dim, Dyn};
use ldcbf_controller::qp::HOT_START_MIN_NV;
use ldcbf_controller::{
    DenseQpOf, DualActiveSetOf, HessianError, QpAllocator, QpSettings, QpStatus, SimpleBoundsOf,
};
use ldcbf_reference::{ProblemError, ProblemView};
use numpy::{PyArray1, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::convert::{float, int_arg, readonly_f64};
use crate::errors::arg_err;

/// Where a solve starts.
#[derive(Clone, Copy)]
enum Warm<'a> {
    /// From scratch.
    Cold,
    /// The rows active or violated at this primal guess `x0` (qpsolvers'
    /// `initvals`) are preferred (`QpSettings::hot_start`).
    Primal(&'a [f64]),
    /// The rows active at the previous solve of the same [`PyQpSolver`] are
    /// preferred, when the stacked row count is unchanged.
    Previous,
}

/// One solve's answer, its multipliers member by member.
struct Answer {
    status: QpStatus,
    x: Vec<f64>,
    /// Stacked multipliers (or the Farkas certificate when infeasible).
    lambda: Vec<f64>,
    objective: f64,
    iterations: u32,
}

/// A solver instance at one size and its storage, kept between solves.
trait SizedSolve: Send + Sync {
    /// Row capacity.
    fn capacity(&self) -> usize;
    /// `static` (a compiled size) or `dynamic`.
    fn path(&self) -> &'static str;
    /// Solves `p` (its stacked rows fit [`SizedSolve::capacity`]).
    fn solve(&mut self, p: &ProblemView<'_>, warm: Warm<'_>) -> Result<Answer, String>;
}

/// A [`SizedSolve`] instance at the dimension types `V`, `C`.
struct Instance<V: Dim, C: Dim>
where
    DefaultAllocator: QpAllocator<V, C>,
{
    solver: DualActiveSetOf<V, C>,
    qp: DenseQpOf<V, C>,
    prefer: Vec<bool>,
    /// Active rows of the last solve and its stacked row count.
    last: (Vec<u16>, usize),
    path: &'static str,
}

impl<V: Dim, C: Dim> Instance<V, C>
where
    DefaultAllocator: QpAllocator<V, C>,
    DualActiveSetOf<V, C>: Send + Sync,
    DenseQpOf<V, C>: Send + Sync,
{
    fn boxed(
        p: &ProblemView<'_>,
        (nv, nc): (V, C),
        settings: QpSettings,
        path: &'static str,
    ) -> Result<Box<dyn SizedSolve>, HessianError> {
        let hess = p.hessian(nv).ok_or(HessianError::BadSize)?;
        let solver = DualActiveSetOf::<V, C>::new(&hess, settings)?;
        let qp = DenseQpOf::<V, C>::with_q_generic(
            ldcbf_controller::nalgebra::OVector::<f64, V>::zeros_generic(
                nv,
                ldcbf_controller::nalgebra::U1,
            ),
            nc,
        );
        Ok(Box::new(Instance {
            solver,
            qp,
            prefer: vec![false; nc.value()],
            last: (Vec::new(), usize::MAX),
            path,
        }))
    }
}

impl<V: Dim, C: Dim> SizedSolve for Instance<V, C>
where
    DefaultAllocator: QpAllocator<V, C>,
    DualActiveSetOf<V, C>: Send + Sync,
    DenseQpOf<V, C>: Send + Sync,
{
    fn capacity(&self) -> usize {
        self.qp.capacity()
    }

    fn path(&self) -> &'static str {
        self.path
    }

    fn solve(&mut self, p: &ProblemView<'_>, warm: Warm<'_>) -> Result<Answer, String> {
        p.write_qp(&mut self.qp).map_err(|e| e.to_string())?;
        let rows = self.qp.m;
        let n = p.n;
        let prefer: &[bool] = match warm {
            Warm::Cold => &[],
            Warm::Primal(x0) => {
                let gt = self.qp.gt.as_slice();
                let h = self.qp.h.as_slice();
                for (i, pr) in self.prefer.iter_mut().enumerate().take(rows) {
                    let g = &gt[i * n..(i + 1) * n];
                    let gx: f64 = g.iter().zip(x0).map(|(a, b)| a * b).sum();
                    // Equalities always; inequalities active or violated at
                    // x0, to a relative 1e-9 of the right-hand side.
                    *pr = i < self.qp.me || gx - h[i] >= -1e-9 * h[i].abs().max(1.0);
                }
                &self.prefer[..rows]
            }
            Warm::Previous if self.last.1 == rows => {
                self.prefer[..rows].fill(false);
                for &a in &self.last.0 {
                    if let Some(pr) = self.prefer.get_mut(usize::from(a)) {
                        *pr = true;
                    }
                }
                &self.prefer[..rows]
            }
            Warm::Previous => &[],
        };
        let sol = if p.lb.is_empty() && p.ub.is_empty() {
            self.solver.solve(&self.qp, prefer)
        } else {
            // The bound rows as simple bounds (the same answer, bit for bit).
            let bounds = SimpleBoundsOf::detect(&self.qp);
            self.solver.solve_bounded(&self.qp, &bounds, prefer)
        };
        self.last.0.clear();
        self.last.0.extend_from_slice(sol.active_set());
        self.last.1 = rows;
        Ok(Answer {
            status: sol.status,
            x: sol.x.as_slice().to_vec(),
            lambda: sol.lambda.iter().take(rows).copied().collect(),
            objective: sol.objective,
            iterations: sol.iterations,
        })
    }
}

/// A solver instance for `p`'s `n` and `rows` stacked rows: the smallest
/// compiled size that holds them and can hold them (equality rows and
/// semidefinite Hessians are compiled in from `HOT_START_MIN_NV` variables
/// on, as in `ldcbf-sim qp solve`), else run-time sized.
fn sized_for(
    p: &ProblemView<'_>,
    rows: usize,
    settings: QpSettings,
) -> Result<Box<dyn SizedSolve>, HessianError> {
    let n = p.n;
    let capable = n >= HOT_START_MIN_NV;
    macro_rules! dispatch {
        ($(($nv:literal, $nc:literal)),*) => {
            $(if n == $nv && rows <= $nc && (p.me == 0 || capable) {
                match Instance::<Const<$nv>, Const<$nc>>::boxed(
                    p, (Const::<$nv>, Const::<$nc>), settings, "static") {
                    // A semidefinite P below HOT_START_MIN_NV: the
                    // run-time-sized instance takes it.
                    Err(HessianError::NotPositiveDefinite) if !capable => {}
                    other => return other,
                }
            })*
        };
    }
    ldcbf_sim::with_qp_sizes!(dispatch);
    Instance::<Dyn, Dyn>::boxed(p, (Dyn(n), Dyn(rows.max(1))), settings, "dynamic")
}

/// The numpy members of a problem, held while borrowed.
struct Members<'py> {
    arrays: [Option<PyReadonlyArrayDyn<'py, f64>>; 8],
    shapes: [Vec<usize>; 8],
}

/// Member names, in [`Members`] order.
const NAMES: [&str; 8] = ["P", "q", "G", "h", "A", "b", "lb", "ub"];

impl<'py> Members<'py> {
    /// Reads the members (None: absent) and checks their shapes.
    fn read(objs: [Option<&Bound<'py, PyAny>>; 8]) -> PyResult<Self> {
        let mut arrays: [Option<PyReadonlyArrayDyn<'py, f64>>; 8] = Default::default();
        let mut shapes: [Vec<usize>; 8] = Default::default();
        for (k, obj) in objs.iter().enumerate() {
            if let Some(o) = obj.filter(|o| !o.is_none()) {
                let a = readonly_f64(o, NAMES[k])?;
                shapes[k] = a.shape().to_vec();
                arrays[k] = Some(a);
            }
        }
        Ok(Members { arrays, shapes })
    }

    fn slice(&self, k: usize) -> &[f64] {
        self.arrays[k]
            .as_ref()
            .and_then(|a| a.as_slice().ok())
            .unwrap_or(&[])
    }

    /// The view, after the shape checks (each error names the member).
    fn view(&self, py: Python<'_>, with_p: bool) -> PyResult<ProblemView<'_>> {
        let shape = |k: usize| self.shapes[k].as_slice();
        let given = |k: usize| self.arrays[k].is_some();
        let n = if with_p {
            match shape(0) {
                [a, b] if a == b && *a > 0 => *a,
                s => {
                    return Err(arg_err(
                        py,
                        "P",
                        format!("expected a square n x n matrix (n >= 1), got shape {s:?}"),
                    ));
                }
            }
        } else {
            shape(1).first().copied().unwrap_or(0)
        };
        if shape(1) != [n] {
            return Err(arg_err(
                py,
                "q",
                format!("expected shape ({n},) to match P, got {:?}", shape(1)),
            ));
        }
        let mut rows = [0usize; 2];
        for (r, (gk, hk)) in [(2usize, 3usize), (4, 5)].into_iter().enumerate() {
            let (g, h) = (NAMES[gk], NAMES[hk]);
            match (given(gk), given(hk)) {
                (false, false) => {}
                (true, false) => {
                    return Err(arg_err(py, h, format!("{g} is given but {h} is not")));
                }
                (false, true) => {
                    return Err(arg_err(py, g, format!("{h} is given but {g} is not")));
                }
                (true, true) => {
                    let m = match shape(hk) {
                        [m] => *m,
                        s => {
                            return Err(arg_err(
                                py,
                                h,
                                format!("expected a vector ({h} of shape (m,)), got shape {s:?}"),
                            ));
                        }
                    };
                    let ok = shape(gk) == [m, n] || (m == 0 && self.slice(gk).is_empty());
                    if !ok {
                        return Err(arg_err(
                            py,
                            g,
                            format!(
                                "expected shape ({m}, {n}) to match {h} and P, got {:?}",
                                shape(gk)
                            ),
                        ));
                    }
                    rows[r] = m;
                }
            }
        }
        for k in [6, 7] {
            if given(k) && shape(k) != [n] {
                return Err(arg_err(
                    py,
                    NAMES[k],
                    format!("expected shape ({n},) to match P, got {:?}", shape(k)),
                ));
            }
        }
        Ok(ProblemView {
            n,
            m: rows[0],
            me: rows[1],
            P: self.slice(0),
            q: self.slice(1),
            G: self.slice(2),
            h: self.slice(3),
            A: self.slice(4),
            b: self.slice(5),
            lb: self.slice(6),
            ub: self.slice(7),
        })
    }
}

/// The solver settings from the keyword arguments (None: the default).
fn settings_from<'py>(
    max_iter: Option<&Bound<'py, PyAny>>,
    tol_primal: Option<&Bound<'py, PyAny>>,
    tol_dependence: Option<&Bound<'py, PyAny>>,
) -> PyResult<QpSettings> {
    let d = QpSettings::default();
    let given = |o: Option<&Bound<'py, PyAny>>| o.filter(|o| !o.is_none()).cloned();
    let settings = QpSettings {
        max_iter: match given(max_iter) {
            None => d.max_iter,
            Some(m) => int_arg(&m, "max_iter", u32::MAX.into())? as u32,
        },
        tol_primal: match given(tol_primal) {
            None => d.tol_primal,
            Some(t) => float(&t, "tol_primal")?,
        },
        tol_dependence: match given(tol_dependence) {
            None => d.tol_dependence,
            Some(t) => float(&t, "tol_dependence")?,
        },
        ..d
    };
    if let Err((field, requirement)) = settings.validate() {
        let py = max_iter.or(tol_primal).or(tol_dependence).map(|o| o.py());
        if let Some(py) = py {
            return Err(arg_err(py, field, requirement));
        }
    }
    Ok(settings)
}

/// A refused Hessian as an `ArgumentError` on `P`.
fn hessian_err(py: Python<'_>, e: HessianError) -> PyErr {
    arg_err(py, "P", e.to_string())
}

/// The result tuple `(status, x, z, y, z_box, objective, iterations)`:
/// `z` of `G x <= h` (length m), `y` of `A x = b` (length me), `z_box` of the
/// bounds (length n; `> 0` upper bound active, `< 0` lower; None without
/// bounds), as qpsolvers' `Solution`. When the status is `infeasible` the
/// multipliers hold the Farkas certificate instead.
type Result7<'py> = (
    &'static str,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Option<Bound<'py, PyArray1<f64>>>,
    f64,
    u32,
);

fn result<'py>(py: Python<'py>, p: &ProblemView<'_>, a: Answer) -> PyResult<Result7<'py>> {
    let split = p
        .split_multipliers(&a.lambda)
        .map_err(|e| arg_err(py, "P", e.to_string()))?;
    let z_box =
        (!p.lb.is_empty() || !p.ub.is_empty()).then(|| PyArray1::from_vec(py, split.z_box()));
    Ok((
        a.status.name(),
        PyArray1::from_vec(py, a.x),
        PyArray1::from_vec(py, split.ineq),
        PyArray1::from_vec(py, split.eq),
        z_box,
        a.objective,
        a.iterations,
    ))
}

/// The entries of `p` checked (finite; bounds not NaN, `lb <= ub`); the
/// error names the member.
fn check(py: Python<'_>, p: &ProblemView<'_>) -> PyResult<()> {
    p.check("member").map_err(|e| {
        let field = match &e {
            ProblemError::MemberLength { key, .. } | ProblemError::MemberValue { key, .. } => *key,
            ProblemError::Bounds { .. } => "lb",
            _ => "P",
        };
        arg_err(py, field, e)
    })
}

/// `initvals` as a primal guess of length `n`.
fn guess<'py>(
    obj: Option<&Bound<'py, PyAny>>,
    n: usize,
) -> PyResult<Option<PyReadonlyArrayDyn<'py, f64>>> {
    let Some(o) = obj.filter(|o| !o.is_none()) else {
        return Ok(None);
    };
    let a = readonly_f64(o, "initvals")?;
    if a.shape() != [n] {
        return Err(arg_err(
            o.py(),
            "initvals",
            format!("expected shape ({n},) to match P, got {:?}", a.shape()),
        ));
    }
    Ok(Some(a))
}

/// One cold solve of `min 1/2 x'Px + q'x  s.t.  Gx <= h, Ax = b, lb <= x <=
/// ub` (see the Python docs of `ldcbf_nav.solve_dense`).
#[pyfunction]
#[pyo3(signature = (P, q, G=None, h=None, A=None, b=None, lb=None, ub=None, initvals=None, *, max_iter=None, tol_primal=None, tol_dependence=None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub(crate) fn solve_dense<'py>(
    py: Python<'py>,
    P: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    G: Option<&Bound<'py, PyAny>>,
    h: Option<&Bound<'py, PyAny>>,
    A: Option<&Bound<'py, PyAny>>,
    b: Option<&Bound<'py, PyAny>>,
    lb: Option<&Bound<'py, PyAny>>,
    ub: Option<&Bound<'py, PyAny>>,
    initvals: Option<&Bound<'py, PyAny>>,
    max_iter: Option<&Bound<'py, PyAny>>,
    tol_primal: Option<&Bound<'py, PyAny>>,
    tol_dependence: Option<&Bound<'py, PyAny>>,
) -> PyResult<Result7<'py>> {
    let settings = settings_from(max_iter, tol_primal, tol_dependence)?;
    let members = Members::read([Some(P), Some(q), G, h, A, b, lb, ub])?;
    let p = members.view(py, true)?;
    check(py, &p)?;
    let x0 = guess(initvals, p.n)?;
    let warm = match &x0 {
        Some(a) => Warm::Primal(a.as_slice().unwrap_or(&[])),
        None => Warm::Cold,
    };
    let mut s = sized_for(&p, p.rows(), settings).map_err(|e| hessian_err(py, e))?;
    let a = s.solve(&p, warm).map_err(|e| arg_err(py, "P", e))?;
    result(py, &p, a)
}

/// A solver for repeated QPs with one cost matrix `P` (see the Python docs of
/// `ldcbf_nav.QpSolver`).
#[pyclass(name = "QpSolver", module = "ldcbf_nav")]
pub(crate) struct PyQpSolver {
    /// `P`, row-major (kept to size a new instance when the rows outgrow it).
    p: Vec<f64>,
    n: usize,
    settings: QpSettings,
    inner: Option<Box<dyn SizedSolve>>,
}

#[pymethods]
impl PyQpSolver {
    #[new]
    #[pyo3(signature = (P, *, max_iter=None, tol_primal=None, tol_dependence=None))]
    #[allow(non_snake_case)]
    fn new(
        py: Python<'_>,
        P: &Bound<'_, PyAny>,
        max_iter: Option<&Bound<'_, PyAny>>,
        tol_primal: Option<&Bound<'_, PyAny>>,
        tol_dependence: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let settings = settings_from(max_iter, tol_primal, tol_dependence)?;
        let a = readonly_f64(P, "P")?;
        let n = match a.shape() {
            [r, c] if r == c && *r > 0 => *r,
            s => {
                return Err(arg_err(
                    py,
                    "P",
                    format!("expected a square n x n matrix (n >= 1), got shape {s:?}"),
                ));
            }
        };
        let p = a.as_slice().map(<[f64]>::to_vec).unwrap_or_default();
        // Factored now, at the run-time size, so that a bad P is refused
        // here; the instance used is chosen at the first solve.
        let q = vec![0.0; n];
        let view = ProblemView {
            n,
            m: 0,
            me: 0,
            P: &p,
            q: &q,
            G: &[],
            h: &[],
            A: &[],
            b: &[],
            lb: &[],
            ub: &[],
        };
        check(py, &view)?;
        sized_for(&view, 0, settings).map_err(|e| hessian_err(py, e))?;
        Ok(PyQpSolver {
            p,
            n,
            settings,
            inner: None,
        })
    }

    /// Number of variables.
    #[getter]
    fn n(&self) -> usize {
        self.n
    }

    /// `static` or `dynamic`: the instance of the last solve (None before).
    #[getter]
    fn path(&self) -> Option<&'static str> {
        self.inner.as_ref().map(|s| s.path())
    }

    /// Solves with this `P`; `warm_start`: `True` (the rows active at the
    /// previous solve, when the row count is unchanged), `False`, or a primal
    /// guess `x0` (rows active or violated there). Returns `(status, x, z, y,
    /// z_box, objective, iterations)` as `solve_dense`.
    #[pyo3(signature = (q, G=None, h=None, A=None, b=None, lb=None, ub=None, *, warm_start=None))]
    #[allow(non_snake_case, clippy::too_many_arguments)]
    fn solve<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        G: Option<&Bound<'py, PyAny>>,
        h: Option<&Bound<'py, PyAny>>,
        A: Option<&Bound<'py, PyAny>>,
        b: Option<&Bound<'py, PyAny>>,
        lb: Option<&Bound<'py, PyAny>>,
        ub: Option<&Bound<'py, PyAny>>,
        warm_start: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Result7<'py>> {
        let members = Members::read([None, Some(q), G, h, A, b, lb, ub])?;
        let mut p = members.view(py, false)?;
        if p.n != self.n {
            return Err(arg_err(
                py,
                "q",
                format!("expected shape ({},) to match P, got ({},)", self.n, p.n),
            ));
        }
        p.P = &self.p;
        check(py, &p)?;
        let x0;
        let warm = match warm_start.filter(|w| !w.is_none()) {
            None => Warm::Previous,
            Some(w) if w.is_instance_of::<pyo3::types::PyBool>() => {
                if w.is_truthy()? {
                    Warm::Previous
                } else {
                    Warm::Cold
                }
            }
            Some(w) => {
                x0 = guess(Some(w), self.n)?;
                match &x0 {
                    Some(a) => Warm::Primal(a.as_slice().unwrap_or(&[])),
                    None => Warm::Cold,
                }
            }
        };
        let rows = p.rows();
        let fits = self.inner.as_ref().is_some_and(|s| {
            s.capacity() >= rows
                && (p.me == 0 || self.n >= HOT_START_MIN_NV || s.path() == "dynamic")
        });
        if !fits {
            self.inner = Some(sized_for(&p, rows, self.settings).map_err(|e| hessian_err(py, e))?);
        }
        let Some(s) = self.inner.as_mut() else {
            return Err(arg_err(py, "P", "no solver instance"));
        };
        let a = s.solve(&p, warm).map_err(|e| arg_err(py, "P", e))?;
        result(py, &p, a)
    }

    fn __repr__(&self) -> String {
        format!("QpSolver(n={})", self.n)
    }
}
