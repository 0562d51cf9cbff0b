//! `ldcbf-sim crowdnav`: the crowd-navigation benchmark of CrowdNav (C. Chen,
//! Y. Liu, S. Kreiss, A. Alahi, "Crowd-Robot Interaction: Crowd-aware Robot
//! Navigation with Attention-based Deep Reinforcement Learning", ICRA 2019),
//! reproduced with our robot.
//!
//! **Protocol.** A case is a seed of the layout
//! ([`crate::world::crowd::families::crowdnav_case`]: circle crossing or
//! square crossing, `humans` ORCA humans of radius 0.3 m); the robot walks
//! from (0, -4) to (0, 4). CrowdNav's humans and robot share
//! `v_pref = 1 m/s` and a time limit of 25 s; our robot walks at about
//! [`NOMINAL_SPEED`] (0.6 m/s), so the humans' preferred speed is
//! `NOMINAL_SPEED` and the time limit `25 s / 0.6` = 41.7 s (both scaled by
//! the same factor; the geometry is CrowdNav's). The robot is invisible to
//! the humans (CrowdNav's main setting) or visible (the humans avoid it as
//! an ORCA agent with its current velocity). The goal is reached within
//! 0.3 m (CrowdNav: the robot's radius).
//!
//! **Robots.** `controller`: our closed loop (the scenario files
//! `scenarios/circle-crossing.toml`, `square-crossing.toml`: delta = 0.05,
//! no planner, `perception` the oracle (the humans' true polygons and
//! velocities) or the LiDAR with tracking); `orca`: CrowdNav's ORCA
//! baseline, a holonomic disk of our body's radius whose velocity is the
//! crate's ORCA velocity toward the goal at `NOMINAL_SPEED`, chosen at the
//! humans' 20 Hz ([`orca_robot`]).
//!
//! **Metrics** ([`CaseRow`], [`Summary`]): success (goal reached without any
//! collision, within the time limit), collision (any contact of the robot
//! with a human; and those the robot caused, [`crate::sim::ContactCause`]),
//! timeout (neither), the mean navigation time of the successes, the
//! discomfort frequency (the fraction of the time, over all cases, in which
//! the robot's body was closer than 0.2 m to a human: CrowdNav's discomfort
//! distance) and the minimum separation (body to body, m; negative in a
//! collision).

use std::ops::Range;

use ldcbf_controller::nalgebra::Vector2;
use rayon::prelude::*;
use serde::Serialize;

use crate::scenario::{LoadOptions, Scenario, ScenarioError, load};
use crate::sense::Perception;
use crate::sim::{ContactCause, Outcome, SimError, SimOptions, run};
use crate::world::crowd::families::{CrowdNavLayout, DISCOMFORT_DIST, crowdnav_case};
use crate::world::people::NOMINAL_SPEED;

pub mod orca_robot;

/// CrowdNav's time limit, s (at `v_pref = 1 m/s`).
pub const CROWDNAV_TIME_LIMIT: f64 = 25.0;
/// CrowdNav's shared preferred speed, m/s.
pub const CROWDNAV_V_PREF: f64 = 1.0;

/// The time limit scaled to our walking speed, s.
pub fn time_limit() -> f64 {
    CROWDNAV_TIME_LIMIT * CROWDNAV_V_PREF / NOMINAL_SPEED
}

/// Who walks the robot's way.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RobotPolicy {
    /// Our controller in the closed loop.
    Controller,
    /// CrowdNav's ORCA robot (holonomic).
    Orca,
}

/// One benchmark setting.
#[derive(Clone, Debug)]
pub struct CrowdNavRequest {
    /// Circle or square crossing.
    pub layout: CrowdNavLayout,
    /// Number of humans.
    pub humans: usize,
    /// The cases (seeds).
    pub cases: Range<u64>,
    /// The humans see the robot.
    pub robot_visible: bool,
    /// The controller's perception (ignored by the ORCA robot).
    pub perception: Perception,
    /// Who walks.
    pub robot: RobotPolicy,
    /// Worker threads.
    pub jobs: usize,
}

/// Why a case could not run.
#[derive(Debug, thiserror::Error)]
pub enum CrowdNavError {
    /// The scenario file of the layout.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The closed loop refused to start.
    #[error("case {seed}: {source}")]
    Run {
        /// The case.
        seed: u64,
        /// Why.
        source: SimError,
    },
    /// The worker pool.
    #[error("thread pool: {0}")]
    Threads(#[from] rayon::ThreadPoolBuildError),
}

/// One case's result.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CaseRow {
    /// The case's seed.
    pub seed: u64,
    /// Goal reached, no collision.
    pub success: bool,
    /// Any contact with a human.
    pub collision: bool,
    /// A contact the robot caused.
    pub robot_collision: bool,
    /// Neither success nor collision.
    pub timeout: bool,
    /// Time the goal was reached, s (successes only).
    pub nav_time: Option<f64>,
    /// Time within [`DISCOMFORT_DIST`] of a human, s.
    pub discomfort_time: f64,
    /// Length of the run, s.
    pub time: f64,
    /// Smallest body-to-body separation from a human, m.
    pub min_separation: f64,
}

impl CaseRow {
    /// The row from a run's facts: outcome, contacts, separations sampled
    /// every `dt` (s).
    fn new(seed: u64, reached: Option<f64>, contacts: (bool, bool), seps: &[f64], dt: f64) -> Self {
        let (collision, robot_collision) = contacts;
        let success = reached.is_some() && !collision;
        CaseRow {
            seed,
            success,
            collision,
            robot_collision,
            timeout: !success && !collision,
            nav_time: reached.filter(|_| success),
            discomfort_time: seps.iter().filter(|&&s| s < DISCOMFORT_DIST).count() as f64 * dt,
            time: seps.len() as f64 * dt,
            min_separation: seps.iter().copied().fold(f64::INFINITY, f64::min),
        }
    }
}

/// The benchmark's figures over the cases.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Number of cases.
    pub cases: usize,
    /// Fraction of successes.
    pub success: f64,
    /// Fraction with any collision.
    pub collision: f64,
    /// Fraction with a collision the robot caused.
    pub robot_collision: f64,
    /// Fraction of timeouts.
    pub timeout: f64,
    /// Mean navigation time of the successes, s (NaN without).
    pub nav_time: f64,
    /// Time within the discomfort distance over all time, all cases.
    pub discomfort: f64,
    /// Smallest separation over all cases, m.
    pub min_separation: f64,
}

/// The summary of `rows`.
pub fn summarize(rows: &[CaseRow]) -> Summary {
    let n = rows.len().max(1) as f64;
    let frac = |f: fn(&CaseRow) -> bool| rows.iter().filter(|r| f(r)).count() as f64 / n;
    let times: Vec<f64> = rows.iter().filter_map(|r| r.nav_time).collect();
    let total: f64 = rows.iter().map(|r| r.time).sum();
    Summary {
        cases: rows.len(),
        success: frac(|r| r.success),
        collision: frac(|r| r.collision),
        robot_collision: frac(|r| r.robot_collision),
        timeout: frac(|r| r.timeout),
        nav_time: if times.is_empty() {
            f64::NAN
        } else {
            times.iter().sum::<f64>() / times.len() as f64
        },
        discomfort: if total > 0.0 {
            rows.iter().map(|r| r.discomfort_time).sum::<f64>() / total
        } else {
            0.0
        },
        min_separation: rows
            .iter()
            .map(|r| r.min_separation)
            .fold(f64::INFINITY, f64::min),
    }
}

/// The scenario of one case for our controller: the layout's file with
/// `perception`, its humans replaced by the case's `humans` (seeing the
/// robot or not).
pub fn case_scenario(req: &CrowdNavRequest, seed: u64) -> Result<Scenario, ScenarioError> {
    let name = match req.layout {
        CrowdNavLayout::Circle => "circle-crossing",
        CrowdNavLayout::Square => "square-crossing",
    };
    let mut sc = load(
        name,
        &LoadOptions {
            seed: Some(seed),
            sets: vec![("perception".into(), format!("{:?}", req.perception.name()))],
        },
    )?;
    let case = crowdnav_case(req.layout, req.humans, seed, sc.robot.body_radius);
    let from = sc.people_from();
    sc.obstacles.truncate(from);
    sc.velocities.truncate(from);
    sc.people = case.people;
    for p in &mut sc.people {
        p.sees_robot = req.robot_visible;
        sc.obstacles.push(p.polygon_at(p.start));
        sc.velocities.push(p.initial_velocity());
    }
    sc.start = case.layout.start;
    sc.goal = case.layout.goal;
    sc.start_heading = case.layout.heading;
    Ok(sc)
}

/// Runs one case with our controller.
fn controller_case(req: &CrowdNavRequest, seed: u64) -> Result<CaseRow, CrowdNavError> {
    let sc = case_scenario(req, seed)?;
    let opts = SimOptions {
        record_clearance: true,
        ..SimOptions::default()
    };
    let r = run(&sc, opts).map_err(|source| CrowdNavError::Run { seed, source })?;
    let reached = (r.outcome == Outcome::GoalReached).then(|| r.sim_time());
    let from = sc.people_from();
    let on_people: Vec<_> = r.contacts.iter().filter(|c| c.obstacle >= from).collect();
    let contacts = (
        !on_people.is_empty(),
        on_people.iter().any(|c| c.cause == ContactCause::Robot),
    );
    // The CoM's clearance to the nearest human polygon, less the body.
    let seps: Vec<f64> = r
        .samples
        .iter()
        .map(|s| s.clearance - sc.robot.body_radius)
        .collect();
    Ok(CaseRow::new(
        seed,
        reached,
        contacts,
        &seps,
        crate::sim::PLANT_DT,
    ))
}

/// Runs every case of `req` (in parallel on `req.jobs` threads), in seed
/// order.
pub fn run_crowdnav(req: &CrowdNavRequest) -> Result<Vec<CaseRow>, CrowdNavError> {
    // Fail on the file before spending the pool.
    if req.robot == RobotPolicy::Controller {
        case_scenario(req, req.cases.start)?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(req.jobs.max(1))
        .build()?;
    let seeds: Vec<u64> = req.cases.clone().collect();
    pool.install(|| {
        seeds
            .par_iter()
            .map(|&seed| match req.robot {
                RobotPolicy::Controller => controller_case(req, seed),
                RobotPolicy::Orca => Ok(orca_robot::case(req, seed)),
            })
            .collect()
    })
}

/// The table's header (Markdown).
pub const TABLE_HEADER: &str = "| layout | humans | robot | perception | robot seen | cases | success | collision (robot-caused) | collision (any) | timeout | nav. time (s) | discomfort | min. separation (m) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|";

/// One Markdown row of `s` for `req`.
pub fn table_row(req: &CrowdNavRequest, s: &Summary) -> String {
    let layout = match req.layout {
        CrowdNavLayout::Circle => "circle",
        CrowdNavLayout::Square => "square",
    };
    let (robot, perception) = match req.robot {
        // With the oracle the controller gets the true velocities (no
        // radius: constant-velocity prediction, no margin); with the LiDAR
        // the tracker's velocities and radii (the reachable-set margin).
        RobotPolicy::Controller => match req.perception {
            Perception::Known => ("ours (CV prediction, no margin)", "oracle"),
            Perception::Lidar => ("ours (tracker, reachable-set margin)", "LiDAR"),
        },
        RobotPolicy::Orca => ("ORCA (holonomic)", "oracle"),
    };
    format!(
        "| {layout} | {} | {robot} | {perception} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {:.4} | {:.3} |",
        req.humans,
        if req.robot_visible {
            "visible"
        } else {
            "invisible"
        },
        s.cases,
        s.success,
        s.robot_collision,
        s.collision,
        s.timeout,
        s.nav_time,
        s.discomfort,
        s.min_separation,
    )
}

/// `rows` as CSV (one line per case).
pub fn csv(rows: &[CaseRow]) -> String {
    let mut out = String::from(
        "seed,success,collision,robot_collision,timeout,nav_time,discomfort_time,time,min_separation\n",
    );
    for r in rows {
        out.push_str(&format!(
            "{},{},{},{},{},{},{:.3},{:.3},{:.4}\n",
            r.seed,
            r.success,
            r.collision,
            r.robot_collision,
            r.timeout,
            r.nav_time.map_or(String::new(), |t| format!("{t:.3}")),
            r.discomfort_time,
            r.time,
            r.min_separation
        ));
    }
    out
}

/// Unit vector of `v`, or zero.
fn unit(v: Vector2<f64>) -> Vector2<f64> {
    let n = v.norm();
    if n > 1e-12 { v / n } else { Vector2::zeros() }
}

#[cfg(test)]
mod tests;
