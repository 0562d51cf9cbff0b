//! The controller settings as a Python dict: `default_config`,
//! `humanoid_config`, and a dict of overrides read into a [`Config`].

use ldcbf_controller::{Config, FieldValue};
use ldcbf_sim::world::robot::RobotParams;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyInt, PyString};

use crate::convert::*;
use crate::errors::*;

/// Names of the [`Config`] fields, in declaration order.
pub(crate) const CONFIG_FIELDS: [&str; 30] = Config::FIELDS;

/// `config` as a dict of all its fields, in declaration order (`None` for the
/// options that are off).
pub(crate) fn config_dict<'py>(py: Python<'py>, c: &Config) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, value) in c.field_values() {
        match value {
            FieldValue::Real(v) => d.set_item(name, v)?,
            FieldValue::Count(v) => d.set_item(name, v)?,
            FieldValue::Flag(v) => d.set_item(name, v)?,
            FieldValue::Optional(v) => d.set_item(name, v)?,
        }
    }
    Ok(d)
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
        let Some(&(field, kind)) = c.field_values().iter().find(|(name, _)| *name == key) else {
            return Err(config_err(
                py,
                &key,
                &format!(
                    "unknown controller setting (known: {})",
                    CONFIG_FIELDS.join(", ")
                ),
            ));
        };
        let value = match kind {
            FieldValue::Real(_) => FieldValue::Real(num(field)?),
            FieldValue::Optional(_) if v.is_none() => FieldValue::Optional(None),
            FieldValue::Optional(_) => FieldValue::Optional(Some(num(field)?)),
            FieldValue::Count(_) => FieldValue::Count(uint(&v, field)?),
            FieldValue::Flag(_) => FieldValue::Flag(
                v.cast::<PyBool>()
                    .map_err(|_| config_err(py, field, "must be True or False"))?
                    .is_true(),
            ),
        };
        c.set_field(field, value)
            .map_err(|_| config_err(py, field, "cannot be set"))?;
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
