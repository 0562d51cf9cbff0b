//! The measured input of one control cycle (docs/maths.md §2.1): the
//! borrowed [`CycleInput`] and its owned, recorded form [`RecordedInput`],
//! the limits of a measurement ([`MAX_RATE`],
//! [`crate::geometry::MAX_COORDINATE`]) with the [`InputError`] naming the
//! input beyond them, and the first stage of the cycle: validating the input
//! and predicting the CoM state `x_0` at the end of the current step.

use nalgebra::Vector2;

use super::{Core, Side};
use crate::geometry::{ConvexPolygon, MAX_COORDINATE};

/// The input of one recorded control cycle, owned: a [`CycleInput`] whose
/// obstacles are named by an index into the caller's obstacle lists. World
/// frame W. The one recorded-input type of the workspace: the simulator's
/// replays (`ldcbf_sim::studies::replay`, lists in `Recording::obstacle_sets`)
/// and the shared test fixtures (`ldcbf_nav::fixtures::walk`) use it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordedInput {
    /// CoM position, m.
    pub com_position: Vector2<f64>,
    /// CoM velocity, m/s.
    pub com_velocity: Vector2<f64>,
    /// Heading, rad (accumulated).
    pub heading: f64,
    /// Turning rate in force, rad/s.
    pub turning_rate: f64,
    /// Stance foot position, m.
    pub stance_foot: Vector2<f64>,
    /// Stance side.
    pub stance_side: Side,
    /// Time already spent in the current step, s.
    pub time_in_step: f64,
    /// Goal given to the controller (the current subgoal), m.
    pub goal: Vector2<f64>,
    /// Index of the cycle's obstacle list among the caller's lists.
    pub obstacles: usize,
    /// The cycle's speed cap, m/s ([`CycleInput::speed_cap`]).
    pub speed_cap: f64,
}

impl RecordedInput {
    /// At rest at the origin, heading 0, left stance foot under the CoM, at the
    /// start of a step, walking to `goal` among obstacle list 0.
    pub fn at_rest(goal: Vector2<f64>) -> RecordedInput {
        RecordedInput {
            com_position: Vector2::zeros(),
            com_velocity: Vector2::zeros(),
            heading: 0.0,
            turning_rate: 0.0,
            stance_foot: Vector2::zeros(),
            stance_side: Side::Left,
            time_in_step: 0.0,
            goal,
            obstacles: 0,
            speed_cap: NO_SPEED_CAP,
        }
    }

    /// This input as ten `f64` bit patterns, `[p_x, p_y, v_x, v_y, heading,
    /// omega, foot_x, foot_y, time_in_step, side]` (m, m/s, rad, rad/s, s,
    /// world frame W; side 0 = left, 1 = right stance foot): the rows the
    /// firmware replays from flash (`firmware/src/recorded.rs`). The goal,
    /// the obstacle list and the speed cap are not kept.
    pub fn to_bits(&self) -> [u64; 10] {
        [
            self.com_position.x.to_bits(),
            self.com_position.y.to_bits(),
            self.com_velocity.x.to_bits(),
            self.com_velocity.y.to_bits(),
            self.heading.to_bits(),
            self.turning_rate.to_bits(),
            self.stance_foot.x.to_bits(),
            self.stance_foot.y.to_bits(),
            self.time_in_step.to_bits(),
            u64::from(self.stance_side == Side::Right),
        ]
    }

    /// The input of a row of [`RecordedInput::to_bits`] (side 1 is the
    /// right foot, any other value the left), walking to `goal` (m, world)
    /// among obstacle list 0 without a speed cap.
    pub fn from_bits(r: &[u64; 10], goal: Vector2<f64>) -> RecordedInput {
        let f = |i: usize| f64::from_bits(r[i]);
        RecordedInput {
            com_position: Vector2::new(f(0), f(1)),
            com_velocity: Vector2::new(f(2), f(3)),
            heading: f(4),
            turning_rate: f(5),
            stance_foot: Vector2::new(f(6), f(7)),
            stance_side: if r[9] == 1 { Side::Right } else { Side::Left },
            time_in_step: f(8),
            goal,
            obstacles: 0,
            speed_cap: NO_SPEED_CAP,
        }
    }

    /// The controller input of this cycle among `obstacles` (the list that
    /// [`RecordedInput::obstacles`] names).
    pub fn input<'a, const V: usize>(
        &self,
        obstacles: &'a [ConvexPolygon<V>],
    ) -> CycleInput<'a, V> {
        CycleInput {
            com_position: self.com_position,
            com_velocity: self.com_velocity,
            heading: self.heading,
            turning_rate: self.turning_rate,
            stance_foot: self.stance_foot,
            stance_side: self.stance_side,
            time_in_step: self.time_in_step,
            goal: self.goal,
            obstacles,
            obstacle_velocities: &[],
            obstacle_velocity_radii: &[],
            speed_cap: self.speed_cap,
        }
    }

    /// [`RecordedInput::input`] with moving obstacles: `velocities[i]` is the
    /// velocity of `obstacles[i]` (m/s, world frame W; see
    /// [`CycleInput::obstacle_velocities`]).
    pub fn input_moving<'a, const V: usize>(
        &self,
        obstacles: &'a [ConvexPolygon<V>],
        velocities: &'a [Vector2<f64>],
    ) -> CycleInput<'a, V> {
        CycleInput {
            obstacle_velocities: velocities,
            ..self.input(obstacles)
        }
    }
}

/// The measured state and context of one control cycle. World frame W.
#[derive(Clone, Copy, Debug)]
pub struct CycleInput<'a, const V: usize> {
    /// CoM position, m.
    pub com_position: Vector2<f64>,
    /// CoM velocity, m/s.
    pub com_velocity: Vector2<f64>,
    /// Heading (yaw), rad.
    pub heading: f64,
    /// Current turning rate (the last commanded `omega`), rad/s.
    pub turning_rate: f64,
    /// Position of the current stance foot, m.
    pub stance_foot: Vector2<f64>,
    /// Which foot is the stance foot.
    pub stance_side: Side,
    /// Time already spent in the current step, s, in `[0, T]` (clamped otherwise).
    pub time_in_step: f64,
    /// Goal or current subgoal, m.
    pub goal: Vector2<f64>,
    /// Obstacles (validated convex polygons, world frame), where they are at
    /// the time of this input.
    pub obstacles: &'a [ConvexPolygon<V>],
    /// Velocity of each obstacle, m/s, world frame W: `obstacle_velocities[i]`
    /// translates `obstacles[i]`, rigidly and at constant velocity over the
    /// whole horizon (no rotation). Empty: every obstacle is at rest (the
    /// static controller, bit for bit). Otherwise its length must equal
    /// `obstacles.len()` (else [`InputError::ObstacleVelocityCount`]), and the
    /// velocity of every obstacle the cycle selects (within
    /// [`Config::r_active`](super::Config::r_active)) must be finite with a
    /// speed of at most [`MAX_RATE`] (else [`InputError::ObstacleVelocity`]);
    /// the velocities of obstacles the cycle does not select are not read.
    pub obstacle_velocities: &'a [Vector2<f64>],
    /// Velocity uncertainty radius of each obstacle, m/s, world frame:
    /// `u_i` says the true velocity of `obstacles[i]` lies within `u_i` of
    /// `obstacle_velocities[i]` (zero when that slice is empty), in any
    /// direction. `u_i > 0` treats the obstacle as a person whose position
    /// lies in the reachable set of docs/maths.md §2.7 (the barrier's margin
    /// grows with it over the horizon, and the robot walks no faster than it
    /// can stop in one step nearby); `u_i = 0` as an obstacle whose velocity
    /// is known and constant (the rows of a moving obstacle, bit for bit).
    /// Empty: every radius 0. Otherwise its length must equal
    /// `obstacles.len()` (else [`InputError::ObstacleVelocityRadiusCount`]),
    /// and the radius of every obstacle the cycle selects must be finite, at
    /// least 0 and at most [`MAX_RATE`] (else
    /// [`InputError::ObstacleVelocityRadius`]); the radii of obstacles the
    /// cycle does not select are not read. Ignored (every radius 0) when
    /// [`Config::velocity_margin`](super::Config::velocity_margin) is off.
    pub obstacle_velocity_radii: &'a [f64],
    /// Speed cap, m/s: an upper bound on the CoM velocity along the heading
    /// at every planned step end (`lon' v_{k+1}`, the walking-velocity row
    /// [`RowKind::VelLonUpper`](crate::constraints::RowKind::VelLonUpper)),
    /// for this cycle only. A host that sees its surroundings as it goes
    /// passes the speed from which the robot can still stop inside the space
    /// it has seen free (the capture-step limit of `docs/safety.md`). The row
    /// takes `min(vx_max, max(c, vx_min))` with `c = speed_cap` when
    /// `speed_cap >= 0`, else `c = 0` (NaN too): a cap never loosens the
    /// configured bound nor crosses the lower one. [`NO_SPEED_CAP`]
    /// (infinity) is the configured bound, bit for bit.
    pub speed_cap: f64,
}

/// [`CycleInput::speed_cap`] of a cycle without a cap (m/s): the configured
/// `vx_max` holds alone.
pub const NO_SPEED_CAP: f64 = f64::INFINITY;

/// Largest accepted CoM speed (m/s), turning rate (rad/s) and obstacle speed
/// (m/s): far beyond any walking robot or person; larger values are treated
/// as corrupted measurements.
pub const MAX_RATE: f64 = 100.0;

/// Which input was not finite or out of its physical range (positions within
/// [`crate::geometry::MAX_COORDINATE`], speed and turning rate within
/// [`MAX_RATE`], heading within `MAX_COORDINATE` rad).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputError {
    /// CoM position, velocity, heading or turning rate.
    State,
    /// Stance foot position.
    StanceFoot,
    /// Time in step.
    TimeInStep,
    /// Goal.
    Goal,
    /// [`CycleInput::obstacle_velocities`] is neither empty nor as long as
    /// [`CycleInput::obstacles`].
    ObstacleVelocityCount,
    /// The velocity of a selected obstacle is not finite or its speed exceeds
    /// [`MAX_RATE`].
    ObstacleVelocity,
    /// [`CycleInput::obstacle_velocity_radii`] is neither empty nor as long
    /// as [`CycleInput::obstacles`].
    ObstacleVelocityRadiusCount,
    /// The velocity uncertainty radius of a selected obstacle is not finite,
    /// negative or larger than [`MAX_RATE`].
    ObstacleVelocityRadius,
    /// Not a measurement: the controller has no valid configuration yet (it
    /// is [`Controller::UNCONFIGURED`](super::Controller::UNCONFIGURED) and
    /// no [`Controller::configure`](super::Controller::configure) has
    /// succeeded).
    NotConfigured,
}

impl core::fmt::Display for InputError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            InputError::State => "CoM state, heading or turning rate is not finite or out of range",
            InputError::StanceFoot => "stance foot position is not finite or out of range",
            InputError::TimeInStep => "time in step is not finite",
            InputError::Goal => "goal is not finite or out of range",
            InputError::ObstacleVelocityCount => {
                "obstacle velocities are neither empty nor one per obstacle"
            }
            InputError::ObstacleVelocity => "an obstacle velocity is not finite or out of range",
            InputError::ObstacleVelocityRadiusCount => {
                "obstacle velocity radii are neither empty nor one per obstacle"
            }
            InputError::ObstacleVelocityRadius => {
                "an obstacle velocity radius is not finite, negative or out of range"
            }
            InputError::NotConfigured => "the controller is not configured",
        })
    }
}

impl core::error::Error for InputError {}

impl<const N: usize, const NV: usize, const NC: usize> Core<N, NV, NC> {
    /// Validates the measured input and predicts `(p_0, v_0, tau)`: the CoM
    /// state at the end of the current step (docs/maths.md §2.1) and the
    /// time left until then, s. Sets `time_clamped` once the time in step is
    /// known to be finite.
    pub(super) fn end_of_step<const V: usize>(
        &self,
        input: &CycleInput<'_, V>,
        time_clamped: &mut bool,
    ) -> Result<(Vector2<f64>, Vector2<f64>, f64), InputError> {
        if !self.configured {
            return Err(InputError::NotConfigured);
        }
        let cfg = &self.config;
        let finite2 = |v: &Vector2<f64>| v.x.is_finite() && v.y.is_finite();
        // `!(x <= bound)` is also true for NaN.
        let within = |v: f64, bound: f64| v.abs() <= bound;
        let pos_ok = |v: &Vector2<f64>| within(v.x, MAX_COORDINATE) && within(v.y, MAX_COORDINATE);
        if !(pos_ok(&input.com_position)
            && within(
                crate::linalg::sqrt(input.com_velocity.norm_squared()),
                MAX_RATE,
            )
            && within(input.heading, MAX_COORDINATE)
            && within(input.turning_rate, MAX_RATE))
        {
            return Err(InputError::State);
        }
        if !pos_ok(&input.stance_foot) {
            return Err(InputError::StanceFoot);
        }
        if !input.time_in_step.is_finite() {
            return Err(InputError::TimeInStep);
        }
        if !pos_ok(&input.goal) {
            return Err(InputError::Goal);
        }
        if !(input.obstacle_velocities.is_empty()
            || input.obstacle_velocities.len() == input.obstacles.len())
        {
            return Err(InputError::ObstacleVelocityCount);
        }
        if !(input.obstacle_velocity_radii.is_empty()
            || input.obstacle_velocity_radii.len() == input.obstacles.len())
        {
            return Err(InputError::ObstacleVelocityRadiusCount);
        }
        let t_step = cfg.step_duration;
        let t_in = crate::linalg::clamp(input.time_in_step, 0.0, t_step);
        *time_clamped = t_in != input.time_in_step;
        let tau = t_step - t_in;

        // 1. Predict x_0 at the end of the current step.
        let (p0, v0) = self.lip.propagate(
            &input.com_position,
            &input.com_velocity,
            &input.stance_foot,
            tau,
        );
        if !(finite2(&p0) && finite2(&v0)) {
            return Err(InputError::State);
        }
        Ok((p0, v0, tau))
    }
}
