//! The summary of a run (`summary.json`, [`Summary`]) and its short human form,
//! and the compute-time percentiles shared with the studies.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Serialize;

use crate::sim::SimResult;

/// Percentiles of the controller's compute time, ns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ComputeStats {
    /// Median (nearest rank), ns.
    pub p50_ns: u64,
    /// 99th percentile (nearest rank), ns.
    pub p99_ns: u64,
    /// Maximum, ns.
    pub max_ns: u64,
    /// Mean, ns.
    pub mean_ns: f64,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Scenario file.
    pub source: String,
    /// Seed used by the scenario's generator.
    pub seed: u64,
    /// QP solver (`own` or `clarabel`).
    pub solver: String,
    /// Controller rate, e.g. `20 Hz` or `once per step`.
    pub mpc_rate: String,
    /// `collided` when the robot moved into a true obstacle
    /// (`contacts_robot > 0`), else why the run ended: `goal_reached`, `time_limit`,
    /// `stuck` or `diverged` (`ended`).
    pub outcome: String,
    /// Why the run ended: `goal_reached`, `time_limit`, `stuck` or `diverged`.
    pub ended: String,
    /// The CoM came within `success_radius` of the goal.
    pub reached_goal: bool,
    /// The body overlapped a true obstacle: some 1 kHz sample had
    /// `min_body_clearance < -`[`crate::world::robot::CONTACT_TOLERANCE`] (for a
    /// point robot, the CoM inside).
    pub collision: bool,
    /// Some footstep's footprint overlapped a true obstacle
    /// (`min_footstep_clearance < -`[`crate::world::robot::CONTACT_TOLERANCE`]).
    pub foot_collision: bool,
    /// Success: the goal reached and no contact where the robot moved into an
    /// obstacle (`contacts_robot == 0`; docs/maths.md §4 for a robot with a body and
    /// feet). On a map at rest every contact is the robot's, so this is
    /// `reached_goal && !collision && !foot_collision`.
    pub success: bool,
    /// Contacts (body or stance foot, [`crate::sim::Contact`]) where the robot
    /// moved into an obstacle: controller failures.
    pub contacts_robot: usize,
    /// Contacts where a moving obstacle moved into a robot that was standing,
    /// moving away or across ([`crate::sim::ContactCause::Obstacle`]).
    pub contacts_person: usize,
    /// Obstacles that move (non-zero velocity).
    pub moving_obstacles: usize,
    /// Radius of the robot's body disk, m (`[robot]`, [`crate::world::robot`]).
    pub body_radius: f64,
    /// Footsteps landed (the initial stance foot not counted).
    pub steps: usize,
    /// Simulated time at the end, s.
    pub sim_time: f64,
    /// Distance from the final CoM to the goal, m.
    pub final_distance: f64,
    /// Minimum over all 1 kHz CoM samples of the signed distance to the nearest
    /// obstacle, m (negative = collision; null without obstacles).
    pub min_com_clearance: Option<f64>,
    /// Time of that minimum, s.
    pub min_com_clearance_time: Option<f64>,
    /// The body's clearance: `min_com_clearance - body_radius`, m (negative =
    /// the body overlapped an obstacle; null without obstacles).
    pub min_body_clearance: Option<f64>,
    /// Minimum over all footsteps (initial stance included) of the signed
    /// clearance of the foot's footprint to the nearest obstacle, m (negative =
    /// a foot overlapping an obstacle; a point foot's distance for a 0 x 0 foot).
    pub min_footstep_clearance: Option<f64>,
    /// Max over every cycle of `CycleInfo::max_violation`: the largest violation of
    /// that cycle's own QP rows (gait + LDCBF) by the plan it returned and the
    /// simulator applied (every cycle's command is sent to the plant); in the rows'
    /// physical units (m/s for velocity rows, m for reachability rows, m of `h`
    /// for LDCBF rows; see `ldcbf_controller::relax`). Cycles that hold
    /// (invalid input, NaN violation) are not counted.
    pub max_violation: f64,
    /// Same, restricted to the cycles whose swing target actually landed (the last
    /// cycle of each step).
    pub max_violation_landed: f64,
    /// Largest gait relaxation of an applied plan, m/s (0 when no cycle was relaxed).
    pub max_relax_gait: f64,
    /// Largest safety (LDCBF) relaxation of an applied plan, m (0 when none).
    pub max_relax_safety: f64,
    /// Largest relaxation of the capturability bound, m/s (0 when none).
    pub max_relax_capture: f64,
    /// Number of cycles per `CycleStatus::name`.
    pub status_counts: BTreeMap<String, usize>,
    /// Number of cycles per command source (`optimal`, `relaxed_gait`,
    /// `relaxed_safety`, `previous_plan`, `capture_step`, `hold`).
    pub source_counts: BTreeMap<String, usize>,
    /// Control cycles run.
    pub cycles: usize,
    /// Controller compute time (wall clock, around the call only; with
    /// `timing_repeats` > 1 each cycle's minimum over that many timings).
    pub compute: ComputeStats,
    /// Timings of each controller call (`run --repeat`, default 1;
    /// `SimOptions::timing_repeats`).
    pub timing_repeats: u32,
    /// Solver iterations: max over cycles.
    pub max_iterations: u32,
    /// Obstacles in the scenario (the true map).
    pub obstacles: usize,
    /// Planner (`none` or `rrt_star`).
    pub planner: String,
    /// Perception (`known` or `lidar`).
    pub perception: String,
    /// Why planning failed, if it did (the run then walked to the goal directly).
    pub planner_error: Option<String>,
    /// What the controller did instead when planning failed: `walked straight
    /// at the goal` (null when planning succeeded or there is no planner).
    pub planner_fallback: Option<String>,
    /// Margin beyond the body radius that found the path, m (null without a plan).
    pub plan_margin: Option<f64>,
    /// Planning attempts made, with smaller margins each (null without a planner).
    pub plan_attempts: Option<u32>,
    /// The path came from the grid search because the RRT* tree did not reach
    /// the goal (null without a plan; `crate::plan`).
    pub plan_grid_searched: Option<bool>,
    /// Wall-clock planning time, ms (null without a planner).
    pub plan_time_ms: Option<f64>,
    /// Nodes of the RRT* tree (null without a plan).
    pub tree_nodes: Option<usize>,
    /// Length of the subgoal polyline from the start, m (null without a plan).
    pub path_length: Option<f64>,
    /// Subgoals handed to the controller, the goal included (1 without a plan).
    pub subgoals: usize,
    /// Subgoals passed (the goal included when reached).
    pub subgoals_reached: usize,
    /// Mean number of obstacles handed to the controller per cycle (the true
    /// count with `known`, the inferred count with `lidar`).
    pub obstacles_seen_mean: f64,
    /// Largest number of obstacles handed to the controller in one cycle.
    pub obstacles_seen_max: usize,
    /// Controller configuration used (defaults + overrides).
    pub config: BTreeMap<String, serde_json::Value>,
    /// The overrides given by the scenario file and `--set`.
    pub overrides: BTreeMap<String, serde_json::Value>,
    /// The scenario's note.
    pub note: String,
    /// The disturbances and what they did (every push with its tick and world
    /// velocity change, foot and estimation error sizes); null when the
    /// scenario has none ([`crate::plant::disturbance`]).
    pub disturbance: Option<crate::plant::disturbance::DisturbanceLog>,
    /// Map updates and plans on the perceived map (null with the known map;
    /// [`super::MappingSummary`]).
    pub mapping: Option<super::MappingSummary>,
}

/// Nearest-rank percentile `p` (0..=100) of `sorted` (ascending), 0 if empty.
pub fn percentile(sorted: &[u64], p: f64) -> u64 {
    nearest_rank(sorted, p).unwrap_or(0)
}

/// Nearest-rank percentile `p` (0..=100) of `sorted` (ascending): the element
/// of rank `ceil(p n / 100)`, at least the first; `None` if empty. Used for
/// compute times here and for clearances in the robustness study.
pub fn nearest_rank<T: Copy>(sorted: &[T], p: f64) -> Option<T> {
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted.get(rank.clamp(1, sorted.len().max(1)) - 1).copied()
}

/// Compute-time statistics of a list of durations (ns).
pub fn compute_stats(ns: &[u64]) -> ComputeStats {
    let mut v = ns.to_vec();
    v.sort_unstable();
    ComputeStats {
        p50_ns: percentile(&v, 50.0),
        p99_ns: percentile(&v, 99.0),
        max_ns: v.last().copied().unwrap_or(0),
        mean_ns: if v.is_empty() {
            0.0
        } else {
            v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64
        },
    }
}

/// Builds the summary of a run.
pub fn summarize(r: &SimResult) -> Summary {
    let sc = &r.scenario;
    let (min_c, min_t) = r
        .samples
        .iter()
        .map(|s| (s.clearance, s.time))
        .fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a });
    let has_obs = !sc.obstacles.is_empty();
    let min_foot = r
        .footsteps
        .iter()
        .map(|f| f.clearance)
        .fold(f64::INFINITY, f64::min);
    let totals = CycleTotals::of(&r.cycles);
    let ns: Vec<u64> = r.cycles.iter().map(|c| c.compute_ns).collect();
    let reached = r.outcome == crate::sim::Outcome::GoalReached;
    let min_body = sc.robot.body_clearance(min_c);
    let tol = crate::world::robot::CONTACT_TOLERANCE;
    let collision = has_obs && min_body < -tol;
    let foot_collision = has_obs && min_foot < -tol;
    let (contacts_robot, contacts_person) = crate::sim::contact_counts(&r.contacts);
    Summary {
        scenario: sc.name.clone(),
        source: sc.source.clone(),
        seed: sc.seed,
        solver: match r.options.solver {
            crate::sim::Solver::Own => "own".into(),
            crate::sim::Solver::Clarabel => "clarabel".into(),
        },
        mpc_rate: r.options.mpc_rate.to_string(),
        outcome: if contacts_robot > 0 {
            "collided".into()
        } else {
            r.outcome.name().into()
        },
        ended: r.outcome.name().into(),
        reached_goal: reached,
        collision,
        foot_collision,
        success: reached && contacts_robot == 0,
        contacts_robot,
        contacts_person,
        moving_obstacles: sc.velocities.iter().filter(|v| v.norm() > 0.0).count(),
        body_radius: sc.robot.body_radius,
        steps: r.steps(),
        sim_time: r.sim_time(),
        final_distance: r.final_distance(),
        min_com_clearance: has_obs.then_some(min_c),
        min_com_clearance_time: has_obs.then_some(min_t),
        min_body_clearance: has_obs.then_some(min_body),
        min_footstep_clearance: has_obs.then_some(min_foot),
        max_violation: totals.max_violation,
        max_violation_landed: totals.max_violation_landed,
        max_relax_gait: totals.max_relax_gait,
        max_relax_safety: totals.max_relax_safety,
        max_relax_capture: totals.max_relax_capture,
        status_counts: totals.status_counts,
        source_counts: totals.source_counts,
        cycles: r.cycles.len(),
        compute: compute_stats(&ns),
        timing_repeats: r.options.timing_repeats,
        max_iterations: r
            .cycles
            .iter()
            .map(|c| c.output.info.iterations)
            .max()
            .unwrap_or(0),
        obstacles: sc.obstacles.len(),
        planner: sc.planner.name().into(),
        perception: sc.perception.name().into(),
        planner_error: r.navigation.error.clone(),
        planner_fallback: r
            .navigation
            .error
            .as_ref()
            .map(|_| "walked straight at the goal (the MPC alone)".to_string()),
        plan_margin: r.navigation.plan.as_ref().map(|p| p.margin_used),
        plan_grid_searched: r.navigation.plan.as_ref().map(|p| p.grid_searched),
        plan_attempts: plan_attempts(r),
        plan_time_ms: (sc.planner != crate::plan::Planner::None)
            .then(|| r.navigation.plan_time_ns as f64 / 1e6),
        tree_nodes: r.navigation.plan.as_ref().map(|p| p.tree.nodes.len()),
        path_length: r
            .navigation
            .plan
            .as_ref()
            .map(|p| p.subgoal_length(sc.start)),
        subgoals: r.navigation.subgoals.len(),
        subgoals_reached: r.navigation.reached_at.len(),
        obstacles_seen_mean: if r.cycles.is_empty() {
            0.0
        } else {
            r.cycles
                .iter()
                .map(|c| c.obstacles_seen as f64)
                .sum::<f64>()
                / r.cycles.len() as f64
        },
        obstacles_seen_max: r.cycles.iter().map(|c| c.obstacles_seen).max().unwrap_or(0),
        config: crate::scenario::config_map(&sc.config),
        overrides: crate::scenario::overrides_map(&sc.controller),
        note: sc.note.clone(),
        disturbance: sc
            .disturbance
            .is_active(sc.config.com_height)
            .then(|| r.disturbance.clone()),
        mapping: r.mapping.as_ref().map(super::summarize_mapping),
    }
}

/// The planner's attempts (margins tried): those of the plan, or every
/// margin when planning failed; `None` without a planner.
fn plan_attempts(r: &SimResult) -> Option<u32> {
    let sc = &r.scenario;
    (sc.planner != crate::plan::Planner::None).then(|| {
        r.navigation.plan.as_ref().map_or(
            crate::plan::attempt_margins(sc.rrt.margin).len() as u32,
            |p| p.attempts,
        )
    })
}

/// What the summary counts over a run's control cycles.
struct CycleTotals {
    /// Cycles per status name.
    status_counts: BTreeMap<String, usize>,
    /// Cycles per command source name.
    source_counts: BTreeMap<String, usize>,
    /// Largest finite row violation of a cycle's command, and of a landed one.
    max_violation: f64,
    max_violation_landed: f64,
    /// Largest relaxations of the priority scheme (gait, safety rows, m;
    /// capturability bound).
    max_relax_gait: f64,
    max_relax_safety: f64,
    max_relax_capture: f64,
}

impl CycleTotals {
    fn of(cycles: &[crate::sim::CycleRecord]) -> CycleTotals {
        let mut t = CycleTotals {
            status_counts: BTreeMap::new(),
            source_counts: BTreeMap::new(),
            max_violation: 0.0,
            max_violation_landed: 0.0,
            max_relax_gait: 0.0,
            max_relax_safety: 0.0,
            max_relax_capture: 0.0,
        };
        for c in cycles {
            let info = &c.output.info;
            t.max_relax_capture = t.max_relax_capture.max(info.relax_capture);
            t.max_relax_gait = t.max_relax_gait.max(info.relax_gait);
            t.max_relax_safety = t.max_relax_safety.max(info.relax_safety);
            *t.status_counts
                .entry(c.output.status.name().to_string())
                .or_insert(0) += 1;
            *t.source_counts
                .entry(info.source.name().to_string())
                .or_insert(0) += 1;
            let v = info.max_violation;
            if v.is_finite() {
                t.max_violation = t.max_violation.max(v);
                if c.landed {
                    t.max_violation_landed = t.max_violation_landed.max(v);
                }
            }
        }
        t
    }
}

/// A short human summary (a few lines).
pub fn human_summary(s: &Summary) -> String {
    let mut o = String::new();
    let _ = writeln!(
        o,
        "scenario {} ({}), solver {}, MPC {}",
        s.scenario, s.source, s.solver, s.mpc_rate
    );
    let feet = if s.foot_collision {
        ", A FOOT ON AN OBSTACLE"
    } else {
        ""
    };
    let verdict = match (s.ended.as_str(), s.collision) {
        ("goal_reached", false) => format!("goal reached{feet}"),
        ("goal_reached", true) => {
            format!("COLLIDED (the body touched an obstacle), then reached the goal{feet}")
        }
        (o, false) => format!("goal NOT reached ({o}){feet}"),
        (o, true) => {
            format!("COLLIDED (the body touched an obstacle), goal NOT reached ({o}){feet}")
        }
    };
    let verdict = if s.moving_obstacles > 0 {
        format!(
            "{verdict}; contacts: {} robot moved into an obstacle, {} a person moved into the robot",
            s.contacts_robot, s.contacts_person
        )
    } else {
        verdict
    };
    let _ = writeln!(
        o,
        "  {verdict}: t = {:.2} s, {} steps, final distance {:.3} m",
        s.sim_time, s.steps, s.final_distance
    );
    if let Some(m) = &s.mapping {
        o.push_str(&super::mapping_line(m));
    }
    if s.planner != "none" && s.mapping.as_ref().is_none_or(|m| m.plans == 0) {
        match &s.planner_error {
            Some(err) => {
                let _ = writeln!(
                    o,
                    "  planner {}: FAILED after {} attempts ({err}); {}",
                    s.planner,
                    s.plan_attempts.unwrap_or(0),
                    s.planner_fallback.as_deref().unwrap_or("")
                );
            }
            None => {
                let _ = writeln!(
                    o,
                    "  planner {}: {} nodes in {:.1} ms, {} subgoals ({} passed), path {:.2} m, margin {:.3} m beyond the body (attempt {}){}",
                    s.planner,
                    s.tree_nodes.unwrap_or(0),
                    s.plan_time_ms.unwrap_or(0.0),
                    s.subgoals,
                    s.subgoals_reached,
                    s.path_length.unwrap_or(0.0),
                    s.plan_margin.unwrap_or(0.0),
                    s.plan_attempts.unwrap_or(0),
                    if s.plan_grid_searched == Some(true) {
                        ", path from the grid search (the tree missed the passage)"
                    } else {
                        ""
                    }
                );
            }
        }
    }
    if s.perception != "known" {
        let _ = writeln!(
            o,
            "  perception {}: {:.1} inferred obstacles per cycle on average (max {}); clearances use the true map",
            s.perception, s.obstacles_seen_mean, s.obstacles_seen_max
        );
    }
    let f = |v: Option<f64>| v.map_or("n/a".to_string(), |x| format!("{x:.3} m"));
    let _ = writeln!(
        o,
        "  min body clearance {} (CoM {}, body radius {:.2} m), min foot clearance {}, max plan violation {:.1e}",
        f(s.min_body_clearance),
        f(s.min_com_clearance),
        s.body_radius,
        f(s.min_footstep_clearance),
        s.max_violation
    );
    let statuses: Vec<String> = s
        .status_counts
        .iter()
        .map(|(k, v)| format!("{k} {v}"))
        .collect();
    let _ = writeln!(
        o,
        "  {} cycles ({}), max {} iterations; compute p50 {:.1} us, p99 {:.1} us, max {:.1} us{}",
        s.cycles,
        statuses.join(", "),
        s.max_iterations,
        s.compute.p50_ns as f64 / 1e3,
        s.compute.p99_ns as f64 / 1e3,
        s.compute.max_ns as f64 / 1e3,
        if s.timing_repeats > 1 {
            format!(" (each cycle's minimum of {} timings)", s.timing_repeats)
        } else {
            String::new()
        }
    );
    if s.source_counts.len() > 1 || !s.source_counts.contains_key("optimal") {
        let src: Vec<String> = s
            .source_counts
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect();
        let _ = writeln!(
            o,
            "  commands: {}; max relaxation gait {:.2e} m/s, safety {:.2e} m, capture {:.2e} m/s",
            src.join(", "),
            s.max_relax_gait,
            s.max_relax_safety,
            s.max_relax_capture
        );
    }
    o
}
