//! The error of a settings table (`[robot]`, `[generator]`, `[rrt_star]`,
//! `[disturbance]`, ...): which field, and what it must satisfy. Here, in the
//! lowest room, because the settings of every room use it.

/// A field of a settings table that is not usable. Displays as
/// `field: requirement`; the scenario loader prefixes the table
/// (`rrt_star.step`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {requirement}")]
pub struct SettingError {
    /// The field, as in the file (`body_radius`, `push_time`, ...).
    pub field: &'static str,
    /// What the field must satisfy (units included).
    pub requirement: String,
}

impl SettingError {
    /// The error of `field`.
    pub fn new(field: &'static str, requirement: impl Into<String>) -> Self {
        SettingError {
            field,
            requirement: requirement.into(),
        }
    }
}
