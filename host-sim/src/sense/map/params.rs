//! The map's settings (the `[lidar.map]` table) and their validation.

use serde::{Deserialize, Serialize};

use crate::world::grid::MAX_CELLS;
use crate::world::setting::SettingError;

/// Mapping settings: the `[lidar.map]` table. Probabilities in (0, 1).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MapParams {
    /// Cell side, m.
    pub resolution: f64,
    /// The map's first box is the bounding box of start and goal grown by
    /// this much on every side, m; with `grow` it then grows with the scans.
    pub padding: f64,
    /// Grow the box when a scan's reach leaves it (default true; false = the
    /// first box is the map for the whole run, cells outside it unknown).
    pub grow: bool,
    /// The most cells the map may hold, in `1..=MAX_CELLS` (20,000,000, 160 MB
    /// at 8 bytes a cell; a run that plans on such a map peaks near 35 bytes a
    /// cell, docs/cli-errors.md); the default is that bound. A growth past it
    /// is refused: the map keeps its box (module docs).
    pub max_cells: usize,
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
    /// A hit makes its cell occupied whatever misses the cell had before
    /// (its log-odds becomes at least one hit's, `logit(p_hit)`), as Nav2's
    /// obstacle layer marks a cell lethal for every point of the current
    /// scan, unless a cell within `hit_noise_band` of it is occupied already
    /// (the hit may then be a noise hit of that obstacle's face). A miss
    /// proves free only its ray's line through a cell, so the misses of rays
    /// beside a thin obstacle (a needle's tip, narrower than a cell) do not
    /// outvote the ray that hits it (default true; docs/safety.md, "A hit is
    /// an obstacle now").
    pub hit_overrides_misses: bool,
    /// With `hit_overrides_misses`: a hit with an occupied cell within this
    /// many metres (rounded up to whole cells, along each axis) counts as
    /// usual (m; default 0.03, three times the default LiDAR's
    /// `noise_sigma`: a noise hit lands within it of its face).
    pub hit_noise_band: f64,
}

impl Default for MapParams {
    fn default() -> Self {
        MapParams {
            resolution: 0.025,
            padding: 3.0,
            grow: true,
            max_cells: MAX_CELLS,
            p_hit: 0.7,
            p_miss: 0.4,
            clamp_min: 0.1192,
            clamp_max: 0.971,
            decay: 0.0,
            unknown_radius: 1.0,
            capture_speed_limit: false,
            hit_overrides_misses: true,
            hit_noise_band: 0.03,
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
        if !(1..=MAX_CELLS).contains(&self.max_cells) {
            return Err(SettingError::new(
                "map.max_cells",
                format!("must be in 1..={MAX_CELLS}"),
            ));
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
        if !(self.hit_noise_band.is_finite() && (0.0..=1.0).contains(&self.hit_noise_band)) {
            return Err(SettingError::new(
                "map.hit_noise_band",
                "must be in [0, 1] m",
            ));
        }
        Ok(())
    }
}
