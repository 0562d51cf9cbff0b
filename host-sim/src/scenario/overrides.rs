//! The `[controller]` table (overrides of [`Config`] fields), the foot side as
//! written in a file, and the configuration and overrides as JSON maps for the
//! logs.

use std::collections::BTreeMap;

use ldcbf_controller::{Config, FieldValue, Side};
use serde::{Deserialize, Serialize};

/// Foot side as written in a file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SideSpec {
    /// Left foot.
    #[default]
    Left,
    /// Right foot.
    Right,
}

impl From<SideSpec> for Side {
    fn from(s: SideSpec) -> Side {
        match s {
            SideSpec::Left => Side::Left,
            SideSpec::Right => Side::Right,
        }
    }
}

/// Overrides of [`Config`] fields (the `[controller]` table). Unset fields keep
/// the paper's defaults ([`Config::default`]). Units as in [`Config`].
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)] // one field per Config field, documented there
pub struct ControllerOverrides {
    pub gravity: Option<f64>,
    pub com_height: Option<f64>,
    pub step_duration: Option<f64>,
    pub vx_min: Option<f64>,
    pub vx_max: Option<f64>,
    pub vy_min: Option<f64>,
    pub vy_max: Option<f64>,
    pub l_max: Option<f64>,
    pub alpha: Option<f64>,
    pub omega_max: Option<f64>,
    pub gamma: Option<f64>,
    pub delta: Option<f64>,
    pub r_active: Option<f64>,
    pub foot_clearance: Option<f64>,
    pub heading_freeze_radius: Option<f64>,
    pub max_iter: Option<u32>,
    pub max_iter_cycle: Option<u32>,
    pub relax_bisections: Option<u32>,
    pub max_gait_relaxation: Option<f64>,
    /// `Config::capture_fraction`; 0 turns the capturability bound off.
    pub capture_fraction: Option<f64>,
    pub warm_start: Option<bool>,
    pub tol_primal: Option<f64>,
    /// `Config::turn_vertex_normals`; unset: on with `perception = "lidar"`
    /// and `planner = "rrt_star"` (the occupancy map and a planned path),
    /// off otherwise (the paper's normal).
    pub turn_vertex_normals: Option<bool>,
    /// `Config::velocity_margin`: `false` is the constant-velocity
    /// prediction with no uncertainty margin (the tracker's radii ignored).
    pub velocity_margin: Option<bool>,
    pub person_speed_max: Option<f64>,
    pub person_accel_max: Option<f64>,
    pub person_reach_time: Option<f64>,
}

/// The robot's fields of [`Config`]: set in `[robot]`
/// ([`crate::world::robot::RobotParams`]), not in `[controller]`.
pub const ROBOT_FIELDS: [&str; 3] = ["body_radius", "foot_length", "foot_width"];

/// Names of the [`Config`] fields that `[controller]` (and `--set`) accept:
/// [`Config::FIELDS`] but the robot's.
pub fn controller_fields() -> impl Iterator<Item = &'static str> {
    Config::FIELDS
        .into_iter()
        .filter(|f| !ROBOT_FIELDS.contains(f))
}

impl ControllerOverrides {
    /// `base` with every set field replaced.
    pub fn apply(&self, base: Config) -> Config {
        let mut c = base;
        macro_rules! set {
            ($($f:ident),*) => { $( if let Some(v) = self.$f { c.$f = v; } )* };
        }
        set!(
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
            heading_freeze_radius,
            max_iter,
            max_iter_cycle,
            relax_bisections,
            max_gait_relaxation,
            warm_start,
            tol_primal,
            turn_vertex_normals,
            velocity_margin,
            person_speed_max,
            person_accel_max,
            person_reach_time
        );
        if let Some(r) = self.capture_fraction {
            c.capture_fraction = (r != 0.0).then_some(r);
        }
        if self.foot_clearance.is_some() {
            c.foot_clearance = self.foot_clearance;
        }
        c
    }
}

/// The configuration as a JSON map (field -> value; `null` for an option that
/// is off).
pub fn config_map(c: &Config) -> BTreeMap<String, serde_json::Value> {
    c.field_values()
        .into_iter()
        .map(|(name, value)| {
            let json = match value {
                FieldValue::Real(v) | FieldValue::Optional(Some(v)) => v.into(),
                FieldValue::Count(v) => v.into(),
                FieldValue::Flag(v) => v.into(),
                FieldValue::Optional(None) => serde_json::Value::Null,
            };
            (name.to_string(), json)
        })
        .collect()
}

/// Summary of the overrides that differ from the defaults, `field -> value`
/// (for logs).
pub fn overrides_map(o: &ControllerOverrides) -> BTreeMap<String, serde_json::Value> {
    match serde_json::to_value(o) {
        Ok(serde_json::Value::Object(m)) => m.into_iter().filter(|(_, v)| !v.is_null()).collect(),
        _ => BTreeMap::new(),
    }
}
