//! `Controller`: the footstep MPC at its compiled sizes, one cycle per
//! `step`, its output as a dict of numpy arrays.

use ldcbf_controller::{
    Config, CycleInput, CycleOutput, CycleStatus, PaperController, QpStatus, RobotController,
};
use ldcbf_sim::scenario::limits::{MAX_ECHO, shorten};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::config::*;
use crate::convert::*;
use crate::errors::*;

/// The compiled controller sizes.
#[derive(Clone, Debug)]
pub(crate) enum AnyController {
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
pub(crate) struct PyController {
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
    /// rest. A count other than the obstacles' (an empty array with
    /// obstacles too) or a non-finite or absurd
    /// velocity is the controller's answer too (`input_error`
    /// `"obstacle_velocity_count"`, `"obstacle_velocity"`).
    /// `obstacle_velocity_radii` (`(n,)`, m/s, one per obstacle): the radius
    /// around each velocity (or around rest) that holds the true velocity,
    /// in any direction (docs/maths.md §2.7: the barrier holds against the
    /// set a person can reach; 0 = known velocity); `None` = all 0. A count
    /// other than the obstacles' or a negative or non-finite radius is the
    /// controller's answer (`"obstacle_velocity_radius_count"`,
    /// `"obstacle_velocity_radius"`).
    #[pyo3(signature = (com_position, com_velocity, heading, turning_rate, stance_foot, stance_side, time_in_step, goal, obstacles=None, obstacle_velocities=None, obstacle_velocity_radii=None))]
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
        obstacle_velocity_radii: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let obstacles = polygons(obstacles)?;
        let velocities = velocities(obstacle_velocities, obstacles.len())?;
        let radii = radii(obstacle_velocity_radii)?;
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
            obstacle_velocity_radii: &radii,
            speed_cap: ldcbf_controller::NO_SPEED_CAP,
        };
        with_controller!(&mut self.inner, c => output_dict(py, &c.step(&input, None)))
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
pub(crate) fn horizon_of<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    _: &ldcbf_controller::Controller<N, NV, NC, NOBS>,
) -> usize {
    N
}

/// The obstacle capacity `NOBS` of a controller type.
pub(crate) fn obstacle_capacity_of<
    const N: usize,
    const NV: usize,
    const NC: usize,
    const NOBS: usize,
>(
    _: &ldcbf_controller::Controller<N, NV, NC, NOBS>,
) -> usize {
    NOBS
}

/// A cycle's output as a dict (see [`PyController::step`]).
pub(crate) fn output_dict<'py, const N: usize>(
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
