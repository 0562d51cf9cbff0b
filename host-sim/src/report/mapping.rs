//! The unknown-map part of the summary: map updates and plans on the
//! perceived map ([`crate::sim::MappingLog`]).

use serde::Serialize;

use crate::sim::MappingLog;

/// Map and planning figures of a run with `perception = "lidar"`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MappingSummary {
    /// Scans added to the map (one per control cycle).
    pub map_updates: usize,
    /// Median wall-clock time of a map update, ms.
    pub map_update_p50_ms: f64,
    /// Largest wall-clock time of a map update, ms.
    pub map_update_max_ms: f64,
    /// Cells of the map seen (free or occupied) at the end, fraction of all.
    pub map_known_fraction: f64,
    /// Cells of the map at the end (8 bytes each).
    pub map_cells: usize,
    /// Times the map's box grew to a scan's reach.
    pub map_grows: usize,
    /// Scans whose reach the box could not grow to (`lidar.map.max_cells`).
    pub map_grows_refused: usize,
    /// Plans on the perceived map (0 without a planner).
    pub plans: usize,
    /// Plans after the first (blocked path or stalled robot).
    pub replans: usize,
    /// Plans that found no path (the robot then walked at the goal).
    pub plan_failures: usize,
    /// Median wall-clock time of a plan, ms (0 without plans).
    pub plan_time_p50_ms: f64,
    /// Largest wall-clock time of a plan, ms.
    pub plan_time_max_ms: f64,
    /// Total wall-clock planning time, ms.
    pub plan_time_total_ms: f64,
}

/// Median and maximum of `ns` in ms (0 when empty).
fn p50_max_ms(ns: &[u64]) -> (f64, f64) {
    let mut s = ns.to_vec();
    s.sort_unstable();
    let p50 = super::nearest_rank(&s, 50.0).unwrap_or(0);
    (
        p50 as f64 / 1e6,
        s.last().copied().unwrap_or(0) as f64 / 1e6,
    )
}

/// The summary of `log`.
pub fn summarize_mapping(log: &MappingLog) -> MappingSummary {
    let (u50, umax) = p50_max_ms(&log.update_ns);
    let plan_ns: Vec<u64> = log.plans.iter().map(|p| p.ns).collect();
    let (p50, pmax) = p50_max_ms(&plan_ns);
    let states = log.map.states();
    let known = states
        .iter()
        .filter(|s| **s != crate::sense::CellState::Unknown)
        .count();
    MappingSummary {
        map_updates: log.update_ns.len(),
        map_update_p50_ms: u50,
        map_update_max_ms: umax,
        map_known_fraction: known as f64 / states.len().max(1) as f64,
        map_cells: states.len(),
        map_grows: log.map.grows(),
        map_grows_refused: log.map.refused_grows(),
        plans: log.plans.len(),
        replans: log.replans(),
        plan_failures: log.failures(),
        plan_time_p50_ms: p50,
        plan_time_max_ms: pmax,
        plan_time_total_ms: plan_ns.iter().sum::<u64>() as f64 / 1e6,
    }
}

/// One line for [`super::human_summary`].
pub fn mapping_line(m: &MappingSummary) -> String {
    format!(
        "  map: {} updates (p50 {:.2} ms, max {:.2} ms), {} cells ({} grows, {} refused), {:.0} % seen; {} plans on the perceived map ({} replans, {} failed; p50 {:.1} ms, max {:.1} ms, total {:.1} ms)\n",
        m.map_updates,
        m.map_update_p50_ms,
        m.map_update_max_ms,
        m.map_cells,
        m.map_grows,
        m.map_grows_refused,
        100.0 * m.map_known_fraction,
        m.plans,
        m.replans,
        m.plan_failures,
        m.plan_time_p50_ms,
        m.plan_time_max_ms,
        m.plan_time_total_ms
    )
}
