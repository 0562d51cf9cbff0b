//! One name for each value of the public enums that hosts write out: the
//! simulator's logs and summaries, the Python package and the C API print
//! these, and only these.
//!
//! Each enum has a `const fn name()`, a short lower-case `snake_case` name;
//! `Display` writes the same name, except for [`InputError`], whose `Display`
//! is a sentence for error messages. The names are part of the hosts'
//! formats (CSV and JSON columns, Python strings, C strings): changing one
//! changes every file written with it.
//!
//! ```
//! use ldcbf_controller::{CommandSource, CycleStatus, InputError, QpStatus, Side};
//!
//! assert_eq!(CycleStatus::BudgetExhausted.name(), "budget_exhausted");
//! assert_eq!(CycleStatus::InvalidInput(InputError::Goal).to_string(), "invalid_input");
//! assert_eq!(format!("{}", CommandSource::CaptureStep), "capture_step");
//! assert_eq!(QpStatus::IterationLimit.name(), "iteration_limit");
//! assert_eq!(InputError::StanceFoot.name(), "stance_foot");
//! assert_eq!(Side::Right.to_string(), "right");
//! ```

use core::fmt;

use crate::mpc::{CommandSource, CycleStatus, InputError, Side};
use crate::qp::QpStatus;

impl CycleStatus {
    /// Short lower-case name, for logs: `optimal`, `infeasible`,
    /// `budget_exhausted`, `numerical_failure`, `invalid_input` (whatever the
    /// [`InputError`]).
    pub const fn name(self) -> &'static str {
        match self {
            CycleStatus::Optimal => "optimal",
            CycleStatus::Infeasible => "infeasible",
            CycleStatus::BudgetExhausted => "budget_exhausted",
            CycleStatus::NumericalFailure => "numerical_failure",
            CycleStatus::InvalidInput(_) => "invalid_input",
        }
    }
}

impl CommandSource {
    /// Short lower-case name, for logs: `optimal`, `relaxed_gait`,
    /// `relaxed_safety`, `previous_plan`, `capture_step`, `hold`.
    pub const fn name(self) -> &'static str {
        match self {
            CommandSource::Optimal => "optimal",
            CommandSource::RelaxedGait => "relaxed_gait",
            CommandSource::RelaxedSafety => "relaxed_safety",
            CommandSource::PreviousPlan => "previous_plan",
            CommandSource::CaptureStep => "capture_step",
            CommandSource::Hold => "hold",
        }
    }
}

impl QpStatus {
    /// Short lower-case name, for logs: `solved`, `infeasible`,
    /// `iteration_limit`, `numerical_error`.
    pub const fn name(self) -> &'static str {
        match self {
            QpStatus::Solved => "solved",
            QpStatus::Infeasible => "infeasible",
            QpStatus::IterationLimit => "iteration_limit",
            QpStatus::NumericalError => "numerical_error",
        }
    }
}

impl InputError {
    /// Short lower-case name of the bad input: `state`, `stance_foot`,
    /// `time_in_step`, `goal`, `not_configured`, `obstacle_velocity_count`,
    /// `obstacle_velocity`, `obstacle_velocity_radius_count`,
    /// `obstacle_velocity_radius` (`Display` gives a sentence).
    pub const fn name(self) -> &'static str {
        match self {
            InputError::State => "state",
            InputError::StanceFoot => "stance_foot",
            InputError::TimeInStep => "time_in_step",
            InputError::Goal => "goal",
            InputError::NotConfigured => "not_configured",
            InputError::ObstacleVelocityCount => "obstacle_velocity_count",
            InputError::ObstacleVelocity => "obstacle_velocity",
            InputError::ObstacleVelocityRadiusCount => "obstacle_velocity_radius_count",
            InputError::ObstacleVelocityRadius => "obstacle_velocity_radius",
        }
    }
}

impl Side {
    /// `left` or `right`.
    pub const fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// `Display` as the value's `name()`.
macro_rules! display_as_name {
    ($($t:ty),*) => {$(
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
    )*};
}

display_as_name!(CycleStatus, CommandSource, QpStatus, Side);
