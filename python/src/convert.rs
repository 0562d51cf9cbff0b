//! Conversions between Python objects and the Rust types: arrays, points,
//! polygons and numbers in (each failure names its argument), numpy arrays and
//! lists out.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{ConvexPolygon, Side};
use ldcbf_sim::scenario::limits::{MAX_ECHO, shorten};
use ldcbf_sim::world::{MAX_VERTICES, Polygon};
use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyList, PyString};

use crate::errors::*;

/// A non-negative integer argument (an `int` or anything with `__index__`,
/// numpy integers included; not a bool, not a float) at most `max`.
pub(crate) fn int_arg(obj: &Bound<'_, PyAny>, field: &str, max: u64) -> PyResult<u64> {
    let py = obj.py();
    let bad = || {
        arg_err(
            py,
            field,
            format!("must be an integer in [0, {max}], got {}", repr(obj)),
        )
    };
    if obj.is_instance_of::<PyBool>() {
        return Err(bad());
    }
    let idx = obj.call_method0("__index__").or_arg(|_| bad())?;
    idx.extract::<u64>()
        .or_arg(|_| bad())
        .and_then(|v| if v <= max { Ok(v) } else { Err(bad()) })
}

/// A string argument.
pub(crate) fn str_arg(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<String> {
    obj.extract::<String>().or_arg(|_| {
        arg_err(
            obj.py(),
            field,
            format!("expected a string, got {}", repr(obj)),
        )
    })
}

/// `obj` as a C-contiguous float64 numpy array, borrowed read-only: read
/// where it lies when it is one, else converted once
/// (`numpy.ascontiguousarray(obj, float64)`). Complex entries are refused
/// (numpy would drop their imaginary parts with only a warning); a
/// conversion failure names `field`.
pub(crate) fn readonly_f64<'py>(
    obj: &Bound<'py, PyAny>,
    field: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f64>>()
        && a.is_c_contiguous()
    {
        return Ok(a.readonly());
    }
    let py = obj.py();
    let np = py.import("numpy")?;
    let arr = np
        .call_method1("asarray", (obj,))
        .or_arg(|e| arg_err(py, field, format!("not an array of numbers ({e})")))?;
    if let Ok(a) = arr.cast::<PyUntypedArray>()
        && a.dtype().kind() == b'c'
    {
        return Err(arg_err(
            py,
            field,
            format!(
                "complex entries are not supported (dtype {}): pass the real part explicitly",
                a.dtype()
            ),
        ));
    }
    let arr = np
        .call_method1("ascontiguousarray", (arr, np.getattr("float64")?))
        .or_arg(|e| arg_err(py, field, format!("not an array of numbers ({e})")))?;
    let arr = arr
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|_| arg_err(py, field, "not an array of float64"))?;
    Ok(arr.readonly())
}

/// `obj` as a C-contiguous float64 array ([`readonly_f64`]): its shape and
/// its entries, copied.
pub(crate) fn float_array(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let ro = readonly_f64(obj, field)?;
    let shape = ro.shape().to_vec();
    let data = ro
        .as_slice()
        .map_err(|e| arg_err(obj.py(), field, e))?
        .to_vec();
    Ok((shape, data))
}

/// A 2-vector (m or m/s): anything numpy reads as two numbers.
pub(crate) fn vec2(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vector2<f64>> {
    let (shape, d) = float_array(obj, field)?;
    if shape != [2] {
        return Err(arg_err(
            obj.py(),
            field,
            format!("expected 2 numbers (x, y), got an array of shape {shape:?}"),
        ));
    }
    Ok(Vector2::new(d[0], d[1]))
}

/// A float (not a bool, not a string).
pub(crate) fn float(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<f64> {
    if obj.is_instance_of::<PyBool>() || obj.is_instance_of::<PyString>() {
        return Err(arg_err(obj.py(), field, "expected a number"));
    }
    obj.extract::<f64>()
        .or_arg(|e| arg_err(obj.py(), field, format!("expected a number ({e})")))
}

/// An `n x 2` vertex array, as `[[x, y], ...]`.
pub(crate) fn points(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vec<[f64; 2]>> {
    let (shape, d) = float_array(obj, field)?;
    if shape.len() != 2 || shape[1] != 2 {
        return Err(arg_err(
            obj.py(),
            field,
            format!("expected an array of vertices of shape (k, 2), got shape {shape:?}"),
        ));
    }
    Ok(d.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
}

/// `"left"` or `"right"`.
pub(crate) fn side(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Side> {
    match obj.extract::<String>().as_deref() {
        Ok("left") => Ok(Side::Left),
        Ok("right") => Ok(Side::Right),
        _ => Err(arg_err(
            obj.py(),
            field,
            format!("expected \"left\" or \"right\", got {}", repr(obj)),
        )),
    }
}

/// `repr(obj)` for a message, shortened ([`shorten`]).
pub(crate) fn repr(obj: &Bound<'_, PyAny>) -> String {
    obj.repr()
        .map(|r| shorten(&r.to_string(), MAX_ECHO))
        .unwrap_or_else(|_| "?".into())
}

/// Validated convex polygons from a sequence of vertex arrays (either
/// orientation, convex), for the controller.
pub(crate) fn polygons(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Polygon>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Vec::new());
    };
    let py = obj.py();
    let iter = obj
        .try_iter()
        .or_arg(|_| arg_err(py, "obstacles", "expected a sequence of vertex arrays"))?;
    let mut out = Vec::new();
    for (i, item) in iter.enumerate() {
        let field = format!("obstacles[{i}]");
        let item = item?;
        let pts = points(&item, &field)?;
        let poly = ConvexPolygon::<MAX_VERTICES>::new(&pts).map_err(|e| {
            arg_err(
                py,
                &field,
                format!("{e} (at most {MAX_VERTICES} vertices, convex, either orientation)"),
            )
        })?;
        out.push(poly);
    }
    Ok(out)
}

/// Obstacle velocities, `(k, 2)` (m/s), for `obstacles` obstacles; `None`:
/// none (every obstacle at rest). A given count `k` other than `obstacles`
/// is left to the controller, which answers `invalid_input`
/// (`obstacle_velocity_count`): an empty array with obstacles too, passed on
/// as `obstacles + 1` zero velocities, since an empty slice means "all at
/// rest" to the controller.
pub(crate) fn velocities(
    obj: Option<&Bound<'_, PyAny>>,
    obstacles: usize,
) -> PyResult<Vec<Vector2<f64>>> {
    const FIELD: &str = "obstacle_velocities";
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Vec::new());
    };
    let (shape, d) = float_array(obj, FIELD)?;
    if shape == [0] || shape == [0, 2] {
        return Ok(vec![
            Vector2::zeros();
            if obstacles > 0 { obstacles + 1 } else { 0 }
        ]);
    }
    if shape.len() != 2 || shape[1] != 2 {
        return Err(arg_err(
            obj.py(),
            FIELD,
            format!("expected one (vx, vy) per obstacle, shape (n, 2), got shape {shape:?}"),
        ));
    }
    Ok(d.chunks_exact(2)
        .map(|c| Vector2::new(c[0], c[1]))
        .collect())
}

/// The obstacles' velocity uncertainty radii (`(n,)`, m/s): empty for
/// `None` or an empty array (every radius 0).
pub(crate) fn radii(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<f64>> {
    const FIELD: &str = "obstacle_velocity_radii";
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Vec::new());
    };
    let (shape, d) = float_array(obj, FIELD)?;
    if shape.len() != 1 {
        return Err(arg_err(
            obj.py(),
            FIELD,
            format!("expected one radius per obstacle, shape (n,), got shape {shape:?}"),
        ));
    }
    Ok(d)
}

// ------------------------------------------------------------------ arrays out

pub(crate) fn arr1<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v)
}

pub(crate) fn arr2<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    v: Vec<f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let a = Array2::from_shape_vec((rows, cols), v)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(a.into_pyarray(py).into_any())
}

/// A numpy array of strings.
pub(crate) fn str_array<'py>(py: Python<'py>, v: Vec<&str>) -> PyResult<Bound<'py, PyAny>> {
    let list = PyList::new(py, v)?;
    py.import("numpy")?.call_method1("array", (list, "U"))
}

/// Polygons as a list of `(k, 2)` arrays.
pub(crate) fn polygon_list<'py>(
    py: Python<'py>,
    polys: &[Polygon],
) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for p in polys {
        let v: Vec<f64> = p.vertices().iter().flat_map(|v| [v.x, v.y]).collect();
        list.append(arr2(py, p.len(), 2, v)?)?;
    }
    Ok(list)
}
