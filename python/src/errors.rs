//! The Python exceptions (`ArgumentError`, `ConfigError`, `ScenarioError`)
//! and the errors that name the bad argument or setting.

use ldcbf_sim::scenario::limits::{MAX_ECHO, shorten};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;

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
pub(crate) fn arg_err(py: Python<'_>, field: &str, msg: impl core::fmt::Display) -> PyErr {
    let field = shorten(field, MAX_ECHO);
    let e = ArgumentError::new_err(format!("{field}: {msg}"));
    let _ = e.value(py).setattr("field", field);
    e
}

/// A conversion's error replaced by an [`ArgumentError`] (or
/// [`ConfigError`]) naming the field, except a `BaseException` that is not an
/// `Exception` (KeyboardInterrupt, SystemExit), which passes through untouched.
pub(crate) trait OrArg<T> {
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

/// A [`ConfigError`] from the controller's error.
pub(crate) fn config_err(py: Python<'_>, field: &str, requirement: &str) -> PyErr {
    let e = ConfigError::new_err(format!(
        "invalid controller setting `{field}`: {requirement}"
    ));
    let v = e.value(py);
    let _ = v.setattr("field", field);
    let _ = v.setattr("requirement", requirement);
    e
}

/// A [`ScenarioError`] from the simulator's error.
pub(crate) fn scenario_err(py: Python<'_>, e: &ldcbf_sim::ScenarioError) -> PyErr {
    let err = ScenarioError::new_err(e.to_string());
    let v = err.value(py);
    let _ = v.setattr("field", e.field.as_str());
    let _ = v.setattr("file", e.file.as_str());
    let _ = v.setattr("line", e.line);
    err
}
