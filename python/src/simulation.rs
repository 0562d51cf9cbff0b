//! Scenarios and closed-loop runs: `load_scenario` and `simulate` (the
//! library behind `ldcbf-sim run`), their results as dicts of numpy columns.

use ldcbf_sim::scenario::limits::{MAX_DEPTH, MAX_ECHO, shorten};
use ldcbf_sim::scenario::{LoadOptions, Scenario};
use ldcbf_sim::sim::{MpcRate, SimOptions, SimResult, Solver};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use crate::config::*;
use crate::convert::*;
use crate::errors::*;

/// A Python value as a TOML value (bool, int, float, str, sequences, dicts;
/// numpy arrays and scalars through `tolist()`); `field` names it in errors.
/// `depth` counts the enclosing dicts and lists: deeper than
/// `ldcbf_sim::scenario::limits::MAX_DEPTH` (a cycle included) is refused
/// before recursing.
pub(crate) fn toml_value(
    obj: &Bound<'_, PyAny>,
    field: &str,
    depth: usize,
) -> PyResult<toml::Value> {
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
pub(crate) fn load(
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
pub(crate) fn scenario_dict<'py>(py: Python<'py>, s: &Scenario) -> PyResult<Bound<'py, PyDict>> {
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
pub(crate) fn load_scenario<'py>(
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
pub(crate) fn simulate<'py>(
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
pub(crate) fn run_interruptible(
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
pub(crate) fn result_dict<'py>(
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

    d.set_item("cycles", cycle_columns(py, &r.cycles)?)?;
    d.set_item("footsteps", footstep_columns(py, &r.footsteps)?)?;
    d.set_item("trajectory", trajectory_columns(py, r, trajectory_every)?)?;

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

/// cycles.csv's columns, unrounded, plus the goal and subgoal given.
fn cycle_columns<'py>(
    py: Python<'py>,
    cy: &[ldcbf_sim::sim::CycleRecord],
) -> PyResult<Bound<'py, PyDict>> {
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
    Ok(cols)
}

/// footsteps.csv's columns.
fn footstep_columns<'py>(
    py: Python<'py>,
    fs: &[ldcbf_sim::sim::Footstep],
) -> PyResult<Bound<'py, PyDict>> {
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
    Ok(cols)
}

/// trajectory.csv's columns: every `trajectory_every`-th sample and the last.
fn trajectory_columns<'py>(
    py: Python<'py>,
    r: &SimResult,
    trajectory_every: usize,
) -> PyResult<Bound<'py, PyDict>> {
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
    Ok(cols)
}

// ------------------------------------------------------------------ QP
