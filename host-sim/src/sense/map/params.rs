//! The map's settings (the `[lidar.map]` table) and their validation.

use serde::{Deserialize, Serialize};

use crate::world::setting::SettingError;

/// Mapping settings: the `[lidar.map]` table. Probabilities in (0, 1).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MapParams {
    /// Cell side, m.
    pub resolution: f64,
    /// The map covers the bounding box of start and goal grown by this much on
    /// every side, m (cells outside it are never updated: unknown).
    pub padding: f64,
    /// Probability of a hit (OctoMap's default 0.7).
    pub p_hit: f64,
    /// Probability of a miss (OctoMap's default 0.4).
    pub p_miss: f64,
    /// Lower clamping probability (OctoMap's 0.1192).
    pub clamp_min: f64,
    /// Upper clamping probability (OctoMap's 0.971).
    pub clamp_max: f64,
    /// Forgetting rate, 1/s: known cells' log-odds shrink by `exp(-decay dt)`
    /// per update (0 = a static world, the default).
    pub decay: f64,
    /// Unknown cells next to a free cell within this distance of the robot
    /// are obstacles for the controller, m (0 = never).
    pub unknown_radius: f64,
    /// The capture-step speed limit (`crate::sim::capture`): each cycle's
    /// speed cap lets the robot stop inside the space seen free along its
    /// planned way (default false: docs/safety.md gives its measured cost).
    pub capture_speed_limit: bool,
}

impl Default for MapParams {
    fn default() -> Self {
        MapParams {
            resolution: 0.025,
            padding: 3.0,
            p_hit: 0.7,
            p_miss: 0.4,
            clamp_min: 0.1192,
            clamp_max: 0.971,
            decay: 0.0,
            unknown_radius: 1.0,
            capture_speed_limit: false,
        }
    }
}

impl MapParams {
    /// Checks every field; the error names the bad one (as `map.FIELD`).
    pub fn validate(&self) -> Result<(), SettingError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let prob = |v: f64| v > 0.0 && v < 1.0;
        if !(pos(self.resolution) && self.resolution <= 1.0) {
            return Err(SettingError::new("map.resolution", "must be in (0, 1] m"));
        }
        if !(self.padding.is_finite() && (0.0..=100.0).contains(&self.padding)) {
            return Err(SettingError::new("map.padding", "must be in [0, 100] m"));
        }
        if !(prob(self.p_hit) && self.p_hit > 0.5) {
            return Err(SettingError::new("map.p_hit", "must be in (0.5, 1)"));
        }
        if !(prob(self.p_miss) && self.p_miss < 0.5) {
            return Err(SettingError::new("map.p_miss", "must be in (0, 0.5)"));
        }
        if !(prob(self.clamp_min) && self.clamp_min < 0.5) {
            return Err(SettingError::new("map.clamp_min", "must be in (0, 0.5)"));
        }
        if !(prob(self.clamp_max) && self.clamp_max > 0.5) {
            return Err(SettingError::new("map.clamp_max", "must be in (0.5, 1)"));
        }
        if !(self.decay.is_finite() && self.decay >= 0.0) {
            return Err(SettingError::new("map.decay", "must be finite and >= 0"));
        }
        if !(self.unknown_radius.is_finite() && self.unknown_radius >= 0.0) {
            return Err(SettingError::new(
                "map.unknown_radius",
                "must be finite and >= 0",
            ));
        }
        Ok(())
    }
}
