//! `solve_qp`: the dense dual active-set QP solver at its compiled sizes or
//! run-time sized.

use ldcbf_controller::nalgebra::{Const, DefaultAllocator, Dim, Dyn};
use ldcbf_controller::{DualActiveSetOf, QpAllocator, QpSettings, QpStatus, SimpleBoundsOf};
use ldcbf_reference::DenseProblem;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::*;
use crate::errors::*;

/// The compiled solver sizes `(NV, max NC)`: the list of `ldcbf-sim qp solve`
/// (any other size is solved by the run-time-sized instance).
pub(crate) const QP_SIZES: [(usize, usize); 7] = ldcbf_sim::studies::qpbench::SIZES;

/// `min 1/2 x'Px + q'x  s.t.  Gx <= h` with the controller's dual active-set
/// solver (`ldcbf_controller::DualActiveSetOf`), cold start: at the smallest
/// compiled size with `n` variables and room for `m` rows, or by the
/// run-time-sized instance (the same code) for any other size. See the
/// Python docs of `ldcbf_nav.solve_qp`.
#[pyfunction]
#[pyo3(signature = (P, q, G=None, h=None, *, max_iter=None, tol_primal=None, tol_dependence=None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
pub(crate) fn solve_qp<'py>(
    py: Python<'py>,
    P: &Bound<'py, PyAny>,
    q: &Bound<'py, PyAny>,
    G: Option<&Bound<'py, PyAny>>,
    h: Option<&Bound<'py, PyAny>>,
    max_iter: Option<&Bound<'py, PyAny>>,
    tol_primal: Option<&Bound<'py, PyAny>>,
    tol_dependence: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let defaults = QpSettings::default();
    let max_iter = match max_iter.filter(|m| !m.is_none()) {
        None => defaults.max_iter,
        Some(m) => int_arg(m, "max_iter", u32::MAX.into())? as u32,
    };
    let tol = |obj: Option<&Bound<'py, PyAny>>, field: &str, default: f64| match obj
        .filter(|t| !t.is_none())
    {
        None => Ok(default),
        Some(t) => float(t, field),
    };
    let settings = QpSettings {
        tol_primal: tol(tol_primal, "tol_primal", defaults.tol_primal)?,
        tol_dependence: tol(tol_dependence, "tol_dependence", defaults.tol_dependence)?,
        max_iter,
        ..defaults
    };
    // The controller's one check of the tolerances.
    if let Err((field, requirement)) = settings.validate() {
        return Err(arg_err(py, field, requirement));
    }
    let (ps, pd) = float_array(P, "P")?;
    if ps.len() != 2 || ps[0] != ps[1] || ps[0] == 0 {
        return Err(arg_err(
            py,
            "P",
            format!("expected a square n x n matrix (n >= 1), got shape {ps:?}"),
        ));
    }
    let n = ps[0];
    let (qs, qd) = float_array(q, "q")?;
    if qs != [n] {
        return Err(arg_err(
            py,
            "q",
            format!("expected shape ({n},) to match P, got {qs:?}"),
        ));
    }
    let (gd, hd, m) = match (G.filter(|g| !g.is_none()), h.filter(|h| !h.is_none())) {
        (None, None) => (Vec::new(), Vec::new(), 0),
        (Some(G), Some(h)) => {
            let (gs, gd) = float_array(G, "G")?;
            let (hs, hd) = float_array(h, "h")?;
            let m = hs.first().copied().unwrap_or(0);
            if hs.len() != 1 {
                return Err(arg_err(
                    py,
                    "h",
                    format!("expected a vector (m,), got shape {hs:?}"),
                ));
            }
            let g_ok = (gs.len() == 2 && gs[0] == m && gs[1] == n) || (m == 0 && gd.is_empty());
            if !g_ok {
                return Err(arg_err(
                    py,
                    "G",
                    format!("expected shape ({m}, {n}) to match h and P, got {gs:?}"),
                ));
            }
            (gd, hd, m)
        }
        (Some(_), None) => return Err(arg_err(py, "h", "G is given but h is not")),
        (None, Some(_)) => return Err(arg_err(py, "G", "h is given but G is not")),
    };
    for (name, v) in [("P", &pd), ("q", &qd), ("G", &gd), ("h", &hd)] {
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return Err(arg_err(
                py,
                name,
                format!("entry {k} (row-major) is not finite"),
            ));
        }
    }
    let data = DenseProblem::inequalities(n, pd, qd, gd, hd);
    macro_rules! dispatch {
        ($(($nv:literal, $nc:literal)),*) => {
            $(if n == $nv && m <= $nc {
                let sol = py.detach(|| solve_sized(&data, (Const::<$nv>, Const::<$nc>), settings, "static"));
                return qp_dict(py, sol.map_err(|e| arg_err(py, "P", e))?, m);
            })*
        };
    }
    ldcbf_sim::with_qp_sizes!(dispatch);
    let sol = py.detach(|| solve_sized(&data, (Dyn(n), Dyn(m)), settings, "dynamic"));
    qp_dict(py, sol.map_err(|e| arg_err(py, "P", e))?, m)
}

/// A solution, sized.
pub(crate) struct QpOut {
    x: Vec<f64>,
    lambda: Vec<f64>,
    objective: f64,
    status: QpStatus,
    iterations: u32,
    active: Vec<u16>,
    /// `static` (a compiled size) or `dynamic`.
    path: &'static str,
}

/// Solves `d` with the instance of dimensions `(nv, nc)` (static or
/// dynamic: the same code).
pub(crate) fn solve_sized<V: Dim, C: Dim>(
    d: &DenseProblem,
    (nv, nc): (V, C),
    settings: QpSettings,
    path: &'static str,
) -> Result<QpOut, String>
where
    DefaultAllocator: QpAllocator<V, C>,
{
    // The reference's one conversion into the solver's types.
    let (hess, qp) = d.to_qp(nv, nc).map_err(|e| e.to_string())?;
    let solver = DualActiveSetOf::<V, C>::new(&hess, settings).map_err(|e| e.to_string())?;
    // The bound rows (`lb`, `ub`) as simple bounds (the same answer as the
    // rows, bit for bit).
    let bounds = SimpleBoundsOf::detect(&qp);
    let sol = solver.solve_bounded(&qp, &bounds, &[]);
    Ok(QpOut {
        x: sol.x.iter().copied().collect(),
        lambda: sol.lambda.iter().take(d.m).copied().collect(),
        objective: sol.objective,
        status: sol.status,
        iterations: sol.iterations,
        active: sol.active_set().to_vec(),
        path,
    })
}

pub(crate) fn qp_dict(py: Python<'_>, s: QpOut, m: usize) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("x", arr1(py, s.x))?;
    debug_assert_eq!(s.lambda.len(), m);
    d.set_item("lambda", arr1(py, s.lambda))?;
    d.set_item("objective", s.objective)?;
    d.set_item("status", s.status.name())?;
    d.set_item("iterations", s.iterations)?;
    let active: Vec<i64> = s.active.iter().map(|&a| i64::from(a)).collect();
    d.set_item("active_set", PyArray1::from_vec(py, active))?;
    d.set_item("path", s.path)?;
    Ok(d)
}
