//! The inputs of an `ldcbf-sim` run as the messages a robot would publish
//! (`/goal_pose`, `/odom`, `/gait_state`, one pair per control cycle), with
//! the command [`NavNode`] answers to each: the data of the DDS test
//! (`ros2/tests/python/test_dds.py`), written as JSON by `ldcbf-ros2 record`.
//!
//! The odometry's twist is in the body frame (`child_frame_id`), as
//! `nav_msgs/Odometry` says; the node turns it back by the yaw of the pose.
//! That round trip (and the quaternion of the heading) may move the last
//! bits of the input, so the expected commands are the node's own on these
//! messages (a fresh controller, cycle after cycle);
//! [`Played::same_as_run`] counts the cycles whose command is also the run's,
//! bit for bit.

use anyhow::{Context, Result};
use ldcbf_controller::RobotController;
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sim::{SimOptions, run};
use ldcbf_sim::studies::replay::Recording;
use serde::Serialize;

use crate::msgs::{
    Covariance, FootstepCommand, GaitState, Header, Odometry, Point, Pose, PoseStamped,
    PoseWithCovariance, Time, Twist, TwistWithCovariance,
};
use crate::node::{NavNode, quaternion};

/// One control cycle: what the robot publishes and what the node answers.
#[derive(Clone, Debug, Serialize)]
pub struct PlayedCycle {
    /// `/odom`.
    pub odom: Odometry,
    /// `/gait_state`.
    pub gait: GaitState,
    /// The node's command.
    pub command: FootstepCommand,
}

/// A recorded run as messages.
#[derive(Clone, Debug, Serialize)]
pub struct Played {
    /// Scenario name.
    pub scenario: String,
    /// `/goal_pose` (published once, before the cycles).
    pub goal: PoseStamped,
    /// The cycles in order.
    pub cycles: Vec<PlayedCycle>,
    /// Cycles whose foot target and turning rate equal the run's, bit for bit.
    pub same_as_run: usize,
}

/// The odometry of a CoM state: position and heading as the pose, the world
/// velocity `v` turned into the body frame `base_link` as the twist.
pub fn odometry(
    stamp: Time,
    frame_id: &str,
    p: Vector2<f64>,
    v: Vector2<f64>,
    heading: f64,
    turning_rate: f64,
) -> Odometry {
    let (s, c) = heading.sin_cos();
    Odometry {
        header: Header {
            stamp,
            frame_id: frame_id.into(),
        },
        child_frame_id: "base_link".into(),
        pose: PoseWithCovariance {
            pose: Pose {
                position: Point {
                    x: p.x,
                    y: p.y,
                    z: 0.0,
                },
                orientation: quaternion(heading),
            },
            covariance: Covariance::default(),
        },
        twist: TwistWithCovariance {
            twist: Twist {
                linear: Point {
                    x: c * v.x + s * v.y,
                    y: -s * v.x + c * v.y,
                    z: 0.0,
                },
                angular: Point {
                    x: 0.0,
                    y: 0.0,
                    z: turning_rate,
                },
            },
            covariance: Covariance::default(),
        },
    }
}

/// Runs `scenario` (known map, no planner: the goal is fixed) with the
/// simulator and turns its cycles into messages in `frame_id`, with the
/// commands a fresh node answers.
pub fn play(scenario: &str, sets: &[(String, String)], frame_id: &str) -> Result<Played> {
    let opts = LoadOptions {
        seed: None,
        sets: sets.to_vec(),
    };
    let sc = load(scenario, &opts)?;
    let res = run(
        &sc,
        SimOptions {
            record_clearance: false,
            ..SimOptions::default()
        },
    )?;
    let rec = Recording::from_run(scenario, &res)?;
    let ctl = RobotController::new(sc.config).map_err(|e| anyhow::anyhow!("{scenario}: {e}"))?;
    let mut nav = NavNode::moving(ctl, sc.obstacles.clone(), &sc.velocities, frame_id)?;
    let goal = PoseStamped {
        header: Header {
            stamp: Time::default(),
            frame_id: frame_id.into(),
        },
        pose: Pose {
            position: Point {
                x: sc.goal.x,
                y: sc.goal.y,
                z: 0.0,
            },
            ..Pose::default()
        },
    };
    let _ = nav.on_goal(&goal);
    let mut cycles = Vec::with_capacity(rec.len());
    let mut same_as_run = 0;
    for (k, (inp, c)) in rec.inputs.iter().zip(&res.cycles).enumerate() {
        anyhow::ensure!(
            inp.goal == sc.goal,
            "{scenario}: cycle {k} walks to a subgoal: record a run without a planner \
             (--set 'planner=\"none\"')"
        );
        let stamp = Time::from_secs(c.time);
        let odom = odometry(
            stamp,
            frame_id,
            inp.com_position,
            inp.com_velocity,
            inp.heading,
            inp.turning_rate,
        );
        let gait = GaitState {
            header: Header {
                stamp,
                frame_id: frame_id.into(),
            },
            stance_side: match inp.stance_side {
                ldcbf_controller::Side::Left => GaitState::LEFT,
                ldcbf_controller::Side::Right => GaitState::RIGHT,
            },
            stance_foot: Point {
                x: inp.stance_foot.x,
                y: inp.stance_foot.y,
                z: 0.0,
            },
            time_in_step: inp.time_in_step,
            turning_rate: inp.turning_rate,
        };
        nav.on_odom(odom.clone());
        let m = nav
            .on_gait(gait.clone())
            .with_context(|| format!("{scenario}: cycle {k}: the node ran no cycle"))?;
        let o = &c.output;
        if m.command.foot_target.x.to_bits() == o.foot_target.x.to_bits()
            && m.command.foot_target.y.to_bits() == o.foot_target.y.to_bits()
            && m.command.turning_rate.to_bits() == o.turning_rate.to_bits()
        {
            same_as_run += 1;
        }
        cycles.push(PlayedCycle {
            odom,
            gait,
            command: m.command,
        });
    }
    Ok(Played {
        scenario: scenario.into(),
        goal,
        cycles,
        same_as_run,
    })
}
