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
//! * [`solve_qp`]: the dense dual active-set QP solver at its compiled sizes;
//!   [`solve_dense`] and [`PyQpSolver`] (`QpSolver`): the same in qpsolvers'
//!   problem form, numpy buffers read in place, `P` factored once for repeated
//!   solves.
//!
//! Every bad argument raises a Python exception (`ArgumentError`, a
//! `ValueError`, or its subclasses `ConfigError` and `ScenarioError`) whose
//! `field` attribute and message name the argument or setting; nothing here
//! panics on user input.
//!
//! Frames and units as in the controller: world frame, m, s, rad.
//!
//! Modules by concern: [`errors`] (the exceptions), [`convert`] (Python objects
//! in, numpy arrays out), [`config`] (the settings dict), [`controller`],
//! [`simulation`] (scenarios and runs), [`qp`], [`dense`].

mod config;
mod controller;
mod convert;
mod dense;
mod errors;
mod qp;
mod simulation;

use pyo3::prelude::*;

use config::{CONFIG_FIELDS, default_config, humanoid_config};
use controller::PyController;
use dense::{PyQpSolver, solve_dense};
use errors::{ArgumentError, ConfigError, ScenarioError};
use qp::{QP_SIZES, solve_qp};
use simulation::{load_scenario, simulate};

/// The native module `ldcbf_nav._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<PyController>()?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(load_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(solve_qp, m)?)?;
    m.add_function(wrap_pyfunction!(solve_dense, m)?)?;
    m.add_class::<PyQpSolver>()?;
    m.add_function(wrap_pyfunction!(default_config, m)?)?;
    m.add_function(wrap_pyfunction!(humanoid_config, m)?)?;
    m.add("ArgumentError", py.get_type::<ArgumentError>())?;
    m.add("ConfigError", py.get_type::<ConfigError>())?;
    m.add("ScenarioError", py.get_type::<ScenarioError>())?;
    m.add("QP_SIZES", QP_SIZES.to_vec())?;
    m.add("CONFIG_FIELDS", CONFIG_FIELDS.to_vec())?;
    Ok(())
}
