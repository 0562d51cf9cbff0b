//! # ldcbf-python
//!
//! The native part (`ldcbf_nav._native`) of the Python package `ldcbf_nav`,
//! built with PyO3 and maturin (`pip install ./python`):
//!
//! * [`PyController`] (`Controller`): the footstep MPC of `ldcbf-controller`,
//!   one [`ldcbf_controller::Controller::step`] per call, numpy arrays in and
//!   out;
//! * [`simulate`]: a closed-loop run of `ldcbf-sim` (the library behind
//!   `ldcbf-sim run`), its logs as numpy columns and its summary;
//! * [`load_scenario`]: a scenario, validated as `ldcbf-sim` loads it;
//! * [`solve_qp`]: the dense dual active-set QP solver at its compiled sizes.
//!
//! Every bad argument raises a Python exception (`ArgumentError`, a
//! `ValueError`, or its subclasses `ConfigError` and `ScenarioError`) whose
//! `field` attribute and message name the argument or setting; nothing here
//! panics on user input.
//!
//! Frames and units as in the controller: world frame, m, s, rad.

use ldcbf_controller::nalgebra::{Const, DefaultAllocator, Dim, Dyn, Vector2};
use ldcbf_controller::{
    Config, ConvexPolygon, CycleInput, CycleOutput, CycleStatus, DualActiveSetOf, PaperController,
    QpAllocator, QpSettings, QpStatus, RobotController, Side,
};
use ldcbf_reference::DenseProblem;
use ldcbf_sim::scenario::limits::{MAX_DEPTH, MAX_ECHO, shorten};
use ldcbf_sim::scenario::{LoadOptions, Scenario};
use ldcbf_sim::sim::{MpcRate, SimOptions, SimResult, Solver};
use ldcbf_sim::world::robot::RobotParams;
use ldcbf_sim::world::{MAX_VERTICES, Polygon};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

create_exception!(
    _native,
    ArgumentError,
    PyValueError,
    "A bad argument: its `field` attribute names the argument or setting (a ValueError)."
);
create_exception!(
    _native,
    ConfigError,
    ArgumentError,
    "An invalid controller setting: `field` names it, `requirement` says what it must satisfy."
);
create_exception!(
    _native,
    ScenarioError,
    ArgumentError,
    "A scenario that cannot be used: `field` (dotted path), `file` and `line` (or None) locate it."
);

/// An [`ArgumentError`] for `field`: the message starts with the field's name
/// (a long one shortened, as the key of a hostile dict can be megabytes).
fn arg_err(py: Python<'_>, field: &str, msg: impl core::fmt::Display) -> PyErr {
    let field = shorten(field, MAX_ECHO);
    let e = ArgumentError::new_err(format!("{field}: {msg}"));
    let _ = e.value(py).setattr("field", field);
    e
}

/// A conversion's error replaced by an [`ArgumentError`] (or
/// [`ConfigError`]) naming the field, except a `BaseException` that is not an
/// `Exception` (KeyboardInterrupt, SystemExit), which passes through untouched.
trait OrArg<T> {
    fn or_arg(self, f: impl FnOnce(PyErr) -> PyErr) -> PyResult<T>;
}

impl<T> OrArg<T> for PyResult<T> {
    fn or_arg(self, f: impl FnOnce(PyErr) -> PyErr) -> PyResult<T> {
        self.map_err(|e| {
            let plain = Python::attach(|py| e.is_instance_of::<PyException>(py));
            if plain { f(e) } else { e }
        })
    }
}

/// A non-negative integer argument (an `int` or anything with `__index__`,
/// numpy integers included; not a bool, not a float) at most `max`.
fn int_arg(obj: &Bound<'_, PyAny>, field: &str, max: u64) -> PyResult<u64> {
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
fn str_arg(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<String> {
    obj.extract::<String>().or_arg(|_| {
        arg_err(
            obj.py(),
            field,
            format!("expected a string, got {}", repr(obj)),
        )
    })
}

/// A [`ConfigError`] from the controller's error.
fn config_err(py: Python<'_>, field: &str, requirement: &str) -> PyErr {
    let e = ConfigError::new_err(format!(
        "invalid controller setting `{field}`: {requirement}"
    ));
    let v = e.value(py);
    let _ = v.setattr("field", field);
    let _ = v.setattr("requirement", requirement);
    e
}

/// A [`ScenarioError`] from the simulator's error.
fn scenario_err(py: Python<'_>, e: &ldcbf_sim::ScenarioError) -> PyErr {
    let err = ScenarioError::new_err(e.to_string());
    let v = err.value(py);
    let _ = v.setattr("field", e.field.as_str());
    let _ = v.setattr("file", e.file.as_str());
    let _ = v.setattr("line", e.line);
    err
}

// ------------------------------------------------------------------ arrays in

/// `obj` as a C-contiguous float64 numpy array (`numpy.ascontiguousarray`),
/// its shape and its entries; a conversion failure names `field`.
fn float_array(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let arr = np
        .call_method1("ascontiguousarray", (obj, np.getattr("float64")?))
        .or_arg(|e| arg_err(py, field, format!("not an array of numbers ({e})")))?;
    let arr = arr
        .cast_into::<numpy::PyArrayDyn<f64>>()
        .map_err(|_| arg_err(py, field, "not an array of float64"))?;
    let shape = arr.shape().to_vec();
    let ro = arr.readonly();
    let data = ro.as_slice().map_err(|e| arg_err(py, field, e))?.to_vec();
    Ok((shape, data))
}

/// A 2-vector (m or m/s): anything numpy reads as two numbers.
fn vec2(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vector2<f64>> {
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
fn float(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<f64> {
    if obj.is_instance_of::<PyBool>() || obj.is_instance_of::<PyString>() {
        return Err(arg_err(obj.py(), field, "expected a number"));
    }
    obj.extract::<f64>()
        .or_arg(|e| arg_err(obj.py(), field, format!("expected a number ({e})")))
}

/// An `n x 2` vertex array, as `[[x, y], ...]`.
fn points(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vec<[f64; 2]>> {
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
fn side(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Side> {
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
fn repr(obj: &Bound<'_, PyAny>) -> String {
    obj.repr()
        .map(|r| shorten(&r.to_string(), MAX_ECHO))
        .unwrap_or_else(|_| "?".into())
}

/// Validated convex polygons from a sequence of vertex arrays (either
/// orientation, convex), for the controller.
fn polygons(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Polygon>> {
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

/// Obstacle velocities, `(n, 2)` (m/s); `None` or an empty array: none
/// (every obstacle at rest).
fn velocities(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Vector2<f64>>> {
    const FIELD: &str = "obstacle_velocities";
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Vec::new());
    };
    let (shape, d) = float_array(obj, FIELD)?;
    if shape == [0] {
        return Ok(Vec::new());
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

// ------------------------------------------------------------------ arrays out

fn arr1<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v)
}

fn arr2<'py>(
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
fn str_array<'py>(py: Python<'py>, v: Vec<&str>) -> PyResult<Bound<'py, PyAny>> {
    let list = PyList::new(py, v)?;
    py.import("numpy")?.call_method1("array", (list, "U"))
}

/// Polygons as a list of `(k, 2)` arrays.
fn polygon_list<'py>(py: Python<'py>, polys: &[Polygon]) -> PyResult<Bound<'py, PyList>> {
    let list = PyList::empty(py);
    for p in polys {
        let v: Vec<f64> = p.vertices().iter().flat_map(|v| [v.x, v.y]).collect();
        list.append(arr2(py, p.len(), 2, v)?)?;
    }
    Ok(list)
}

// ------------------------------------------------------------------ config

/// Names of the [`Config`] fields, in declaration order.
const CONFIG_FIELDS: [&str; 25] = Config::FIELDS;

/// The `f64` fields of [`Config`], as `(name, accessor)` pairs, written once.
macro_rules! f64_fields {
    ($m:ident) => {
        $m!(
            gravity,
            com_height,
            step_duration,
            vx_min,
            vx_max,
            vy_min,
            vy_max,
            l_max,
            alpha,
            omega_max,
            gamma,
            delta,
            r_active,
            body_radius,
            foot_length,
            foot_width,
            heading_freeze_radius,
            max_gait_relaxation,
            tol_primal
        )
    };
}

/// `config` as a dict of all its fields (`None` for the options that are off).
fn config_dict<'py>(py: Python<'py>, c: &Config) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    macro_rules! put {
        ($($f:ident),*) => { $( d.set_item(stringify!($f), c.$f)?; )* };
    }
    f64_fields!(put);
    d.set_item("foot_clearance", c.foot_clearance)?;
    d.set_item("capture_fraction", c.capture_fraction)?;
    d.set_item("max_iter", c.max_iter)?;
    d.set_item("max_iter_cycle", c.max_iter_cycle)?;
    d.set_item("relax_bisections", c.relax_bisections)?;
    d.set_item("warm_start", c.warm_start)?;
    // Same keys, same order as the Rust struct.
    let ordered = PyDict::new(py);
    for k in CONFIG_FIELDS {
        if let Some(v) = d.get_item(k)? {
            ordered.set_item(k, v)?;
        }
    }
    Ok(ordered)
}

/// A non-negative integer that fits `u32` (not a bool).
fn uint(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<u32> {
    if obj.is_instance_of::<PyBool>() || !obj.is_instance_of::<PyInt>() {
        return Err(config_err(obj.py(), field, "must be an integer"));
    }
    obj.extract::<u32>()
        .or_arg(|_| config_err(obj.py(), field, "must be an integer in [0, 2^32)"))
}

/// `base` with the settings of the mapping `obj` (field name -> value); any
/// field left out keeps `base`'s value. Unknown names, wrong types and values
/// [`Config::validate`] refuses raise [`ConfigError`] naming the field.
fn config_from(py: Python<'_>, obj: Option<&Bound<'_, PyAny>>, base: Config) -> PyResult<Config> {
    let mut c = base;
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        c.validate()
            .map_err(|e| config_err(py, e.field, e.requirement))?;
        return Ok(c);
    };
    let map = obj
        .cast::<PyDict>()
        .map_err(|_| arg_err(py, "config", "expected a dict of controller settings"))?;
    for (k, v) in map.iter() {
        let key: String = k.extract().or_arg(|_| {
            arg_err(
                py,
                "config",
                format!("setting names are strings, got {}", repr(&k)),
            )
        })?;
        // Numbers, numpy scalars included; not bools, not strings.
        let num = |field: &str| -> PyResult<f64> {
            if v.is_instance_of::<PyBool>() || v.is_instance_of::<PyString>() {
                return Err(config_err(py, field, "must be a number"));
            }
            v.extract::<f64>()
                .or_arg(|_| config_err(py, field, "must be a number"))
        };
        macro_rules! set_f64 {
            ($($f:ident),*) => {
                match key.as_str() {
                    $( stringify!($f) => { c.$f = num(stringify!($f))?; continue; } )*
                    _ => {}
                }
            };
        }
        f64_fields!(set_f64);
        match key.as_str() {
            "foot_clearance" => {
                c.foot_clearance = if v.is_none() {
                    None
                } else {
                    Some(num("foot_clearance")?)
                };
            }
            "capture_fraction" => {
                c.capture_fraction = if v.is_none() {
                    None
                } else {
                    Some(num("capture_fraction")?)
                };
            }
            "max_iter" => c.max_iter = uint(&v, "max_iter")?,
            "max_iter_cycle" => c.max_iter_cycle = uint(&v, "max_iter_cycle")?,
            "relax_bisections" => c.relax_bisections = uint(&v, "relax_bisections")?,
            "warm_start" => {
                c.warm_start = v
                    .cast::<PyBool>()
                    .map_err(|_| config_err(py, "warm_start", "must be True or False"))?
                    .is_true();
            }
            other => {
                return Err(config_err(
                    py,
                    other,
                    &format!(
                        "unknown controller setting (known: {})",
                        CONFIG_FIELDS.join(", ")
                    ),
                ));
            }
        }
    }
    c.validate()
        .map_err(|e| config_err(py, e.field, e.requirement))?;
    Ok(c)
}

/// The controller's defaults: the paper's Table I, a point robot
/// (`ldcbf_controller::Config::default()`).
#[pyfunction]
fn default_config(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    config_dict(py, &Config::default())
}

/// The simulator's default humanoid: the controller's defaults with the body
/// disk (0.25 m) and the feet (0.22 x 0.10 m) of `[robot]`'s defaults and the
/// foot rows on (`ldcbf_sim::world::robot::RobotParams::default().apply(..)`).
#[pyfunction]
fn humanoid_config(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    config_dict(py, &RobotParams::default().apply(Config::default()))
}

// ------------------------------------------------------------------ controller

/// The compiled controller sizes.
#[derive(Clone, Debug)]
enum AnyController {
    /// `RobotController`: N = 3, 8 obstacles, room for the foot rows (NC = 72).
    Robot(Box<RobotController>),
    /// `PaperController`: N = 3, 8 obstacles, no foot rows (NC = 48).
    Paper(Box<PaperController>),
}

/// Calls `$body` with `$c` bound to the concrete controller.
macro_rules! with_controller {
    ($any:expr, $c:ident => $body:expr) => {
        match $any {
            AnyController::Robot($c) => $body,
            AnyController::Paper($c) => $body,
        }
    };
}

/// The LDCBF footstep MPC (`ldcbf_controller::Controller`), one `step` per
/// control cycle. `Controller(config=None, *, size="robot")`: `config` is a
/// dict of settings over the controller's defaults (`default_config()`);
/// `size` is `"robot"` (horizon 3, 8 obstacles, foot rows possible: the
/// simulator's `RobotController`) or `"paper"` (horizon 3, 8 obstacles, no
/// foot rows: `PaperController`).
#[pyclass(module = "ldcbf_nav._native", name = "Controller")]
struct PyController {
    inner: AnyController,
    size: &'static str,
}

#[pymethods]
impl PyController {
    #[new]
    #[pyo3(signature = (config=None, *, size=None))]
    fn new(
        py: Python<'_>,
        config: Option<&Bound<'_, PyAny>>,
        size: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let size = match size.filter(|s| !s.is_none()) {
            None => "robot".to_string(),
            Some(s) => str_arg(s, "size")?,
        };
        let cfg = config_from(py, config, Config::default())?;
        let map = |e: ldcbf_controller::ConfigError| config_err(py, e.field, e.requirement);
        let (inner, size) = match size.as_str() {
            "robot" => (
                AnyController::Robot(Box::new(RobotController::new(cfg).map_err(map)?)),
                "robot",
            ),
            "paper" => (
                AnyController::Paper(Box::new(PaperController::new(cfg).map_err(map)?)),
                "paper",
            ),
            other => {
                return Err(arg_err(
                    py,
                    "size",
                    format!(
                        "expected \"robot\" or \"paper\", got {:?}",
                        shorten(other, MAX_ECHO)
                    ),
                ));
            }
        };
        Ok(PyController { inner, size })
    }

    /// The configuration in use, a dict of every setting.
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        with_controller!(&self.inner, c => config_dict(py, c.config()))
    }

    /// `"robot"` or `"paper"`.
    #[getter]
    fn size(&self) -> &'static str {
        self.size
    }

    /// Horizon `N`: footsteps planned per cycle.
    #[getter]
    fn horizon(&self) -> usize {
        with_controller!(&self.inner, c => horizon_of(c.as_ref()))
    }

    /// Obstacle capacity: at most this many (the nearest) are used per cycle.
    #[getter]
    fn obstacle_capacity(&self) -> usize {
        with_controller!(&self.inner, c => obstacle_capacity_of(c.as_ref()))
    }

    /// Forgets the warm-start and fallback memory (as a new controller).
    fn reset(&mut self) {
        with_controller!(&mut self.inner, c => c.reset())
    }

    /// One control cycle. World frame, m, m/s, rad, rad/s, s. Returns a dict:
    /// `foot_target` (2,), `turning_rate`, `status`, `input_error`, `plan`
    /// (`x0` (5,), `states` (N, 5) as `[px, py, vx, vy, theta]`, `feet`
    /// (N, 2), `first_side`) and `info` (the cycle's diagnostics). A NaN or
    /// out-of-range measurement is not an exception: the controller answers
    /// with status `"invalid_input"` and the hold command, as onboard.
    /// `obstacle_velocities` (`(n, 2)`, m/s, world frame, one per obstacle):
    /// the obstacles' constant velocities over the horizon; `None` = all at
    /// rest. A count other than the obstacles' or a non-finite or absurd
    /// velocity is the controller's answer too (`input_error`
    /// `"obstacle_velocity_count"`, `"obstacle_velocity"`).
    #[pyo3(signature = (com_position, com_velocity, heading, turning_rate, stance_foot, stance_side, time_in_step, goal, obstacles=None, obstacle_velocities=None))]
    #[allow(clippy::too_many_arguments)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        com_position: &Bound<'py, PyAny>,
        com_velocity: &Bound<'py, PyAny>,
        heading: &Bound<'py, PyAny>,
        turning_rate: &Bound<'py, PyAny>,
        stance_foot: &Bound<'py, PyAny>,
        stance_side: &Bound<'py, PyAny>,
        time_in_step: &Bound<'py, PyAny>,
        goal: &Bound<'py, PyAny>,
        obstacles: Option<&Bound<'py, PyAny>>,
        obstacle_velocities: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let obstacles = polygons(obstacles)?;
        let velocities = velocities(obstacle_velocities)?;
        let input = CycleInput {
            com_position: vec2(com_position, "com_position")?,
            com_velocity: vec2(com_velocity, "com_velocity")?,
            heading: float(heading, "heading")?,
            turning_rate: float(turning_rate, "turning_rate")?,
            stance_foot: vec2(stance_foot, "stance_foot")?,
            stance_side: side(stance_side, "stance_side")?,
            time_in_step: float(time_in_step, "time_in_step")?,
            goal: vec2(goal, "goal")?,
            obstacles: &obstacles,
            obstacle_velocities: &velocities,
        };
        with_controller!(&mut self.inner, c => output_dict(py, &c.step(&input)))
    }

    fn __repr__(&self) -> String {
        format!(
            "Controller(size={:?}, horizon={})",
            self.size,
            self.horizon()
        )
    }
}

/// The horizon `N` of a controller type.
fn horizon_of<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    _: &ldcbf_controller::Controller<N, NV, NC, NOBS>,
) -> usize {
    N
}

/// The obstacle capacity `NOBS` of a controller type.
fn obstacle_capacity_of<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    _: &ldcbf_controller::Controller<N, NV, NC, NOBS>,
) -> usize {
    NOBS
}

/// A cycle's output as a dict (see [`PyController::step`]).
fn output_dict<'py, const N: usize>(
    py: Python<'py>,
    o: &CycleOutput<N>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "foot_target",
        arr1(py, vec![o.foot_target.x, o.foot_target.y]),
    )?;
    d.set_item("turning_rate", o.turning_rate)?;
    d.set_item("status", o.status.name())?;
    d.set_item(
        "input_error",
        match o.status {
            CycleStatus::InvalidInput(e) => Some(e.name()),
            _ => None,
        },
    )?;
    let plan = PyDict::new(py);
    let x0 = &o.plan.x0;
    plan.set_item(
        "x0",
        arr1(
            py,
            vec![
                x0.position.x,
                x0.position.y,
                x0.velocity.x,
                x0.velocity.y,
                x0.heading,
            ],
        ),
    )?;
    let states: Vec<f64> = o
        .plan
        .states
        .iter()
        .flat_map(|s| {
            [
                s.position.x,
                s.position.y,
                s.velocity.x,
                s.velocity.y,
                s.heading,
            ]
        })
        .collect();
    plan.set_item("states", arr2(py, N, 5, states)?)?;
    let feet: Vec<f64> = o.plan.feet.iter().flat_map(|f| [f.x, f.y]).collect();
    plan.set_item("feet", arr2(py, N, 2, feet)?)?;
    plan.set_item("first_side", o.plan.first_side.name())?;
    d.set_item("plan", plan)?;
    let i = &o.info;
    let info = PyDict::new(py);
    info.set_item("qp_status", i.qp_status.map(QpStatus::name))?;
    info.set_item("iterations", i.iterations)?;
    info.set_item("active_set_size", i.active_set_size)?;
    info.set_item("active_obstacles", i.active_obstacles)?;
    info.set_item("obstacles_truncated", i.obstacles_truncated)?;
    info.set_item("inside_obstacle", i.inside_obstacle)?;
    info.set_item("time_clamped", i.time_clamped)?;
    info.set_item("warm_started", i.warm_started)?;
    info.set_item("source", i.source.name())?;
    info.set_item("cost", i.cost)?;
    info.set_item("max_violation", i.max_violation)?;
    info.set_item("min_h0", i.min_h0)?;
    info.set_item("relax_gait", i.relax_gait)?;
    info.set_item("relax_safety", i.relax_safety)?;
    info.set_item("relax_capture", i.relax_capture)?;
    d.set_item("info", info)?;
    Ok(d)
}

// ------------------------------------------------------------------ scenarios

/// A Python value as a TOML value (bool, int, float, str, sequences, dicts;
/// numpy arrays and scalars through `tolist()`); `field` names it in errors.
/// `depth` counts the enclosing dicts and lists: deeper than
/// `ldcbf_sim::scenario::limits::MAX_DEPTH` (a cycle included) is refused
/// before recursing.
fn toml_value(obj: &Bound<'_, PyAny>, field: &str, depth: usize) -> PyResult<toml::Value> {
    let py = obj.py();
    if depth > MAX_DEPTH {
        return Err(arg_err(
            py,
            field,
            format!("nested more than {MAX_DEPTH} dicts or lists deep (or contains itself)"),
        ));
    }
    if obj.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(obj.is_truthy()?));
    }
    if obj.is_instance_of::<PyInt>() {
        return obj
            .extract::<i64>()
            .map(toml::Value::Integer)
            .or_arg(|_| arg_err(py, field, "integer out of range"));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(float(obj, field)?));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_str()?.to_string()));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, v) in d.iter() {
            let k: String = k
                .extract()
                .or_arg(|_| arg_err(py, field, format!("keys are strings, got {}", repr(&k))))?;
            let sub = if field.is_empty() {
                k.clone()
            } else {
                format!("{field}.{k}")
            };
            t.insert(k, toml_value(&v, &sub, depth + 1)?);
        }
        return Ok(toml::Value::Table(t));
    }
    if obj.is_none() {
        return Err(arg_err(
            py,
            field,
            "None has no scenario value (leave the key out)",
        ));
    }
    if obj.hasattr("tolist")? {
        let native = obj.call_method0("tolist")?;
        return toml_value(&native, field, depth + 1);
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut a = Vec::new();
        for (i, v) in obj.try_iter()?.enumerate() {
            a.push(toml_value(&v?, &format!("{field}[{i}]"), depth + 1)?);
        }
        return Ok(toml::Value::Array(a));
    }
    Err(arg_err(
        py,
        field,
        format!("cannot be used in a scenario: {}", repr(obj)),
    ))
}

/// Loads the scenario: a name or path (as `ldcbf-sim run`), or a dict with
/// the keys of a scenario file; `sets` are `--set key=value` overrides.
fn load(
    py: Python<'_>,
    scenario: &Bound<'_, PyAny>,
    seed: Option<&Bound<'_, PyAny>>,
    sets: Option<&Bound<'_, PyDict>>,
) -> PyResult<Scenario> {
    let seed = match seed.filter(|s| !s.is_none()) {
        None => None,
        Some(s) => Some(int_arg(s, "seed", u64::MAX)?),
    };
    let mut opts = LoadOptions {
        seed,
        sets: Vec::new(),
    };
    if let Some(sets) = sets {
        for (k, v) in sets.iter() {
            let key: String = k.extract().or_arg(|_| {
                arg_err(
                    py,
                    "overrides",
                    format!("keys are strings, got {}", repr(&k)),
                )
            })?;
            let value = toml_value(&v, &key, 0)?;
            opts.sets.push((key, value.to_string()));
        }
    }
    let result = if let Ok(spec) = scenario.extract::<String>() {
        ldcbf_sim::scenario::load(&spec, &opts)
    } else if let Ok(d) = scenario.cast::<PyDict>() {
        let toml::Value::Table(table) = toml_value(d.as_any(), "", 0)? else {
            return Err(arg_err(py, "scenario", "expected a dict"));
        };
        let text = toml::to_string(&table).map_err(|e| arg_err(py, "scenario", e))?;
        ldcbf_sim::scenario::parse_str(&text, "<dict>", &opts)
    } else {
        return Err(arg_err(
            py,
            "scenario",
            format!(
                "expected a scenario name, a path or a dict, got {}",
                repr(scenario)
            ),
        ));
    };
    result.map_err(|e| scenario_err(py, &e))
}

/// The scenario as a dict (see `load_scenario`).
fn scenario_dict<'py>(py: Python<'py>, s: &Scenario) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &s.name)?;
    d.set_item("description", &s.description)?;
    d.set_item("note", &s.note)?;
    d.set_item("source", &s.source)?;
    d.set_item("start", arr1(py, vec![s.start.x, s.start.y]))?;
    d.set_item("start_heading", s.start_heading)?;
    d.set_item("stance", s.stance.name())?;
    d.set_item("goal", arr1(py, vec![s.goal.x, s.goal.y]))?;
    d.set_item("time_limit", s.time_limit)?;
    d.set_item("success_radius", s.success_radius)?;
    d.set_item("stuck_window", s.stuck_window)?;
    d.set_item("planner", s.planner.name())?;
    d.set_item("perception", s.perception.name())?;
    d.set_item("seed", s.seed)?;
    d.set_item("config", config_dict(py, &s.config)?)?;
    let robot = PyDict::new(py);
    robot.set_item("body_radius", s.robot.body_radius)?;
    robot.set_item("foot_length", s.robot.foot_length)?;
    robot.set_item("foot_width", s.robot.foot_width)?;
    robot.set_item("keep_feet_clear", s.robot.keep_feet_clear)?;
    d.set_item("robot", robot)?;
    d.set_item("obstacles", polygon_list(py, &s.obstacles)?)?;
    Ok(d)
}

/// Loads and validates a scenario as `ldcbf-sim` does. See the Python
/// wrapper `ldcbf_nav.load_scenario`.
#[pyfunction]
#[pyo3(signature = (scenario, seed=None, sets=None))]
fn load_scenario<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    seed: Option<&Bound<'py, PyAny>>,
    sets: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = load(py, scenario, seed, sets)?;
    scenario_dict(py, &s)
}

/// Runs a scenario in closed loop (`ldcbf_sim::run`, as `ldcbf-sim run`
/// without the figures). See the Python wrapper `ldcbf_nav.simulate`.
#[pyfunction]
#[pyo3(signature = (scenario, seed=None, sets=None, solver=None, mpc_rate=None, trajectory_every=None))]
fn simulate<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyAny>,
    seed: Option<&Bound<'py, PyAny>>,
    sets: Option<&Bound<'py, PyDict>>,
    solver: Option<&Bound<'py, PyAny>>,
    mpc_rate: Option<&Bound<'py, PyAny>>,
    trajectory_every: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let solver = match solver.filter(|s| !s.is_none()) {
        None => "own".to_string(),
        Some(s) => str_arg(s, "solver")?,
    };
    let trajectory_every = match trajectory_every.filter(|t| !t.is_none()) {
        None => 1,
        Some(t) => int_arg(t, "trajectory_every", u32::MAX.into())? as usize,
    };
    let solver = match solver.as_str() {
        "own" => Solver::Own,
        "clarabel" => Solver::Clarabel,
        other => {
            return Err(arg_err(
                py,
                "solver",
                format!(
                    "expected \"own\" or \"clarabel\", got {:?}",
                    shorten(other, MAX_ECHO)
                ),
            ));
        }
    };
    let mpc_rate = match mpc_rate.filter(|r| !r.is_none()) {
        None => MpcRate::Hz(20),
        Some(r) => {
            let text = if r.is_instance_of::<PyBool>() {
                String::new()
            } else if let Ok(s) = r.extract::<String>() {
                s
            } else if r.is_instance_of::<PyInt>() {
                int_arg(r, "mpc_rate", u32::MAX.into())?.to_string()
            } else {
                String::new()
            };
            text.parse::<MpcRate>()
                .map_err(|e| arg_err(py, "mpc_rate", format!("{e} (got {})", repr(r))))?
        }
    };
    if trajectory_every == 0 {
        return Err(arg_err(py, "trajectory_every", "must be >= 1"));
    }
    let sc = load(py, scenario, seed, sets)?;
    let options = SimOptions {
        solver,
        mpc_rate,
        record_scans: false,
        record_qps: false,
        record_clearance: true,
        timing_repeats: 1,
    };
    let result = run_interruptible(py, &sc, options)?.map_err(|e| arg_err(py, "scenario", e))?;
    result_dict(py, &result, trajectory_every)
}

/// `ldcbf_sim::run` on a worker thread, without the GIL, while this thread
/// checks for Python signals every 50 ms: a signal handler's exception (Ctrl-C's
/// KeyboardInterrupt) cancels the run (`ldcbf_sim::sim::cancel`, polled every
/// tick) and is raised as it came.
fn run_interruptible(
    py: Python<'_>,
    sc: &Scenario,
    options: SimOptions,
) -> PyResult<Result<SimResult, ldcbf_sim::sim::SimError>> {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    let flag = Arc::new(AtomicBool::new(false));
    std::thread::scope(|s| {
        let worker = {
            let flag = Arc::clone(&flag);
            s.spawn(move || ldcbf_sim::sim::cancel::with_flag(flag, || ldcbf_sim::run(sc, options)))
        };
        while !worker.is_finished() {
            py.detach(|| std::thread::sleep(std::time::Duration::from_millis(50)));
            if let Err(e) = py.check_signals() {
                flag.store(true, Ordering::Relaxed);
                let _ = worker.join();
                return Err(e);
            }
        }
        worker
            .join()
            .map_err(|_| pyo3::exceptions::PyRuntimeError::new_err("the simulation panicked"))
    })
}

/// A run's logs as dicts of numpy columns (see `ldcbf_nav.simulate`).
fn result_dict<'py>(
    py: Python<'py>,
    r: &SimResult,
    trajectory_every: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let summary = ldcbf_sim::summarize(r);
    let json = serde_json::to_string(&summary).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let d = PyDict::new(py);
    d.set_item("outcome", r.outcome.name())?;
    d.set_item(
        "summary",
        py.import("json")?.call_method1("loads", (json,))?,
    )?;

    // cycles.csv's columns, unrounded, plus the goal and subgoal given.
    let cy = &r.cycles;
    let cols = PyDict::new(py);
    let f = |g: &dyn Fn(&ldcbf_sim::sim::CycleRecord) -> f64| arr1(py, cy.iter().map(g).collect());
    let i = |g: &dyn Fn(&ldcbf_sim::sim::CycleRecord) -> i64| {
        PyArray1::from_vec(py, cy.iter().map(g).collect::<Vec<i64>>())
    };
    let b = |g: &dyn Fn(&ldcbf_sim::sim::CycleRecord) -> bool| {
        PyArray1::from_vec(py, cy.iter().map(g).collect::<Vec<bool>>())
    };
    cols.set_item("index", i(&|c| c.index as i64))?;
    cols.set_item("t", f(&|c| c.time))?;
    cols.set_item("time_in_step", f(&|c| c.time_in_step))?;
    cols.set_item("step", i(&|c| i64::from(c.step)))?;
    cols.set_item(
        "stance",
        str_array(py, cy.iter().map(|c| c.stance_side.name()).collect())?,
    )?;
    cols.set_item("x0_px", f(&|c| c.output.plan.x0.position.x))?;
    cols.set_item("x0_py", f(&|c| c.output.plan.x0.position.y))?;
    cols.set_item("x0_vx", f(&|c| c.output.plan.x0.velocity.x))?;
    cols.set_item("x0_vy", f(&|c| c.output.plan.x0.velocity.y))?;
    cols.set_item("x0_theta", f(&|c| c.output.plan.x0.heading))?;
    cols.set_item(
        "active_obstacles",
        i(&|c| i64::from(c.output.info.active_obstacles)),
    )?;
    cols.set_item("truncated", b(&|c| c.output.info.obstacles_truncated))?;
    cols.set_item(
        "status",
        str_array(py, cy.iter().map(|c| c.output.status.name()).collect())?,
    )?;
    cols.set_item(
        "source",
        str_array(py, cy.iter().map(|c| c.output.info.source.name()).collect())?,
    )?;
    cols.set_item("iterations", i(&|c| i64::from(c.output.info.iterations)))?;
    cols.set_item(
        "active_set",
        i(&|c| i64::from(c.output.info.active_set_size)),
    )?;
    cols.set_item(
        "compute_ns",
        i(&|c| i64::try_from(c.compute_ns).unwrap_or(i64::MAX)),
    )?;
    cols.set_item("max_violation", f(&|c| c.output.info.max_violation))?;
    cols.set_item("cost", f(&|c| c.output.info.cost))?;
    cols.set_item("min_h0", f(&|c| c.output.info.min_h0))?;
    cols.set_item("relax_gait", f(&|c| c.output.info.relax_gait))?;
    cols.set_item("relax_safety", f(&|c| c.output.info.relax_safety))?;
    cols.set_item("relax_capture", f(&|c| c.output.info.relax_capture))?;
    cols.set_item("foot_x", f(&|c| c.output.foot_target.x))?;
    cols.set_item("foot_y", f(&|c| c.output.foot_target.y))?;
    cols.set_item("omega", f(&|c| c.output.turning_rate))?;
    cols.set_item("landed", b(&|c| c.landed))?;
    cols.set_item("goal_x", f(&|c| c.goal.x))?;
    cols.set_item("goal_y", f(&|c| c.goal.y))?;
    cols.set_item("subgoal", i(&|c| c.subgoal as i64))?;
    cols.set_item("obstacles_seen", i(&|c| c.obstacles_seen as i64))?;
    d.set_item("cycles", cols)?;

    let fs = &r.footsteps;
    let cols = PyDict::new(py);
    cols.set_item(
        "step",
        PyArray1::from_vec(
            py,
            fs.iter().map(|s| i64::from(s.index)).collect::<Vec<_>>(),
        ),
    )?;
    cols.set_item(
        "side",
        str_array(py, fs.iter().map(|s| s.side.name()).collect())?,
    )?;
    cols.set_item("x", arr1(py, fs.iter().map(|s| s.position.x).collect()))?;
    cols.set_item("y", arr1(py, fs.iter().map(|s| s.position.y).collect()))?;
    cols.set_item("t", arr1(py, fs.iter().map(|s| s.time).collect()))?;
    cols.set_item("heading", arr1(py, fs.iter().map(|s| s.heading).collect()))?;
    cols.set_item(
        "clearance",
        arr1(py, fs.iter().map(|s| s.clearance).collect()),
    )?;
    d.set_item("footsteps", cols)?;

    // Every n-th sample and the last, as trajectory.csv.
    let n = r.samples.len();
    let sm: Vec<_> = r
        .samples
        .iter()
        .enumerate()
        .filter(|(k, _)| k % trajectory_every == 0 || k + 1 == n)
        .map(|(_, s)| s)
        .collect();
    let cols = PyDict::new(py);
    cols.set_item("t", arr1(py, sm.iter().map(|s| s.time).collect()))?;
    cols.set_item("px", arr1(py, sm.iter().map(|s| s.position.x).collect()))?;
    cols.set_item("py", arr1(py, sm.iter().map(|s| s.position.y).collect()))?;
    cols.set_item("vx", arr1(py, sm.iter().map(|s| s.velocity.x).collect()))?;
    cols.set_item("vy", arr1(py, sm.iter().map(|s| s.velocity.y).collect()))?;
    cols.set_item("theta", arr1(py, sm.iter().map(|s| s.heading).collect()))?;
    cols.set_item(
        "omega",
        arr1(py, sm.iter().map(|s| s.turning_rate).collect()),
    )?;
    cols.set_item(
        "stance",
        str_array(py, sm.iter().map(|s| s.stance_side.name()).collect())?,
    )?;
    cols.set_item(
        "clearance",
        arr1(py, sm.iter().map(|s| s.clearance).collect()),
    )?;
    d.set_item("trajectory", cols)?;

    let sg: Vec<f64> = r
        .navigation
        .subgoals
        .iter()
        .flat_map(|g| [g.x, g.y])
        .collect();
    d.set_item("subgoals", arr2(py, r.navigation.subgoals.len(), 2, sg)?)?;
    d.set_item("scenario", scenario_dict(py, &r.scenario)?)?;
    Ok(d)
}

// ------------------------------------------------------------------ QP

/// The compiled solver sizes `(NV, max NC)`: the list of `ldcbf-sim qp solve`
/// (any other size is solved by the run-time-sized instance).
const QP_SIZES: [(usize, usize); 7] = ldcbf_sim::studies::qpbench::SIZES;

/// `min 1/2 x'Px + q'x  s.t.  Gx <= h` with the controller's dual active-set
/// solver (`ldcbf_controller::DualActiveSetOf`), cold start: at the smallest
/// compiled size with `n` variables and room for `m` rows, or by the
/// run-time-sized instance (the same code) for any other size. See the
/// Python docs of `ldcbf_nav.solve_qp`.
#[pyfunction]
#[pyo3(signature = (P, q, G=None, h=None, *, max_iter=None, tol_primal=None, tol_dependence=None))]
#[allow(non_snake_case, clippy::too_many_arguments)]
fn solve_qp<'py>(
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
struct QpOut {
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
fn solve_sized<V: Dim, C: Dim>(
    d: &DenseProblem,
    (nv, nc): (V, C),
    settings: QpSettings,
    path: &'static str,
) -> Result<QpOut, String>
where
    DefaultAllocator: QpAllocator<V, C>,
{
    // The reference's one conversion into the solver's types.
    let (hess, qp) = d.to_qp(nv, nc).map_err(|e| e.0)?;
    let solver = DualActiveSetOf::<V, C>::new(&hess, settings).map_err(|e| e.to_string())?;
    let sol = solver.solve(&qp, &[]);
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

fn qp_dict(py: Python<'_>, s: QpOut, m: usize) -> PyResult<Bound<'_, PyDict>> {
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

/// The native module `ldcbf_nav._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<PyController>()?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(load_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(solve_qp, m)?)?;
    m.add_function(wrap_pyfunction!(default_config, m)?)?;
    m.add_function(wrap_pyfunction!(humanoid_config, m)?)?;
    m.add("ArgumentError", py.get_type::<ArgumentError>())?;
    m.add("ConfigError", py.get_type::<ConfigError>())?;
    m.add("ScenarioError", py.get_type::<ScenarioError>())?;
    m.add("QP_SIZES", QP_SIZES.to_vec())?;
    m.add("CONFIG_FIELDS", CONFIG_FIELDS.to_vec())?;
    Ok(())
}
