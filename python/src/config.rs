//! The controller settings as a Python dict: `default_config`,
//! `humanoid_config`, and a dict of overrides read into a [`Config`].

use ldcbf_controller::Config;
use ldcbf_sim::world::robot::RobotParams;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyInt, PyString};

use crate::convert::*;
use crate::errors::*;

/// Names of the [`Config`] fields, in declaration order.
pub(crate) const CONFIG_FIELDS: [&str; 25] = Config::FIELDS;

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
pub(crate) fn config_dict<'py>(py: Python<'py>, c: &Config) -> PyResult<Bound<'py, PyDict>> {
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
pub(crate) fn uint(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<u32> {
    if obj.is_instance_of::<PyBool>() || !obj.is_instance_of::<PyInt>() {
        return Err(config_err(obj.py(), field, "must be an integer"));
    }
    obj.extract::<u32>()
        .or_arg(|_| config_err(obj.py(), field, "must be an integer in [0, 2^32)"))
}

/// `base` with the settings of the mapping `obj` (field name -> value); any
/// field left out keeps `base`'s value. Unknown names, wrong types and values
/// [`Config::validate`] refuses raise [`ConfigError`] naming the field.
pub(crate) fn config_from(
    py: Python<'_>,
    obj: Option<&Bound<'_, PyAny>>,
    base: Config,
) -> PyResult<Config> {
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
pub(crate) fn default_config(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    config_dict(py, &Config::default())
}

/// The simulator's default humanoid: the controller's defaults with the body
/// disk (0.25 m) and the feet (0.22 x 0.10 m) of `[robot]`'s defaults and the
/// foot rows on (`ldcbf_sim::world::robot::RobotParams::default().apply(..)`).
#[pyfunction]
pub(crate) fn humanoid_config(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    config_dict(py, &RobotParams::default().apply(Config::default()))
}

// ------------------------------------------------------------------ controller
