//! ldcbf-nav as a ROS 2 node in pure Rust (ros2-client over RustDDS, no ROS
//! installation needed): docs/ros2.md.
//!
//! * [`msgs`]: the ROS 2 messages (standard ones and `ldcbf_msgs`), field for
//!   field;
//! * [`node`]: the node's logic without DDS (messages <-> controller, the cycle);
//! * [`guard`]: refused inputs (counted, logged) and clock jumps;
//! * [`params`]: the YAML parameter file (ROS 2 layout);
//! * [`record`]: the inputs of an `ldcbf-sim` run as messages, with the
//!   commands the node must answer (the DDS test's data);
//! * [`scan`]: `/scan` through the project's perception;
//! * [`robot`]: the robot stand-in (the simulator's plant) without DDS;
//! * [`dds`]: topics, QoS and the node's loop on DDS.

pub mod dds;
pub mod guard;
pub mod msgs;
pub mod node;
pub mod params;
pub mod record;
pub mod robot;
pub mod scan;

use anyhow::{Context, Result};
use ldcbf_controller::RobotController;
use ldcbf_sim::scenario::{LoadOptions, load};

use crate::node::NavNode;
use crate::params::Params;

/// The node of `params`: the controller configured by the map scenario, its
/// obstacles (and their velocities) as the known map (or, with `perception: lidar`, its `[lidar]`
/// settings for the perception of `/scan`).
pub fn nav_node(params: &Params) -> Result<NavNode> {
    let sc = load(
        &params.map,
        &LoadOptions {
            seed: None,
            sets: params.sets.clone(),
        },
    )
    .with_context(|| format!("map {}", params.map))?;
    let ctl = RobotController::new(sc.config)
        .map_err(|e| anyhow::anyhow!("map {}: controller: {e}", params.map))?;
    let nav = NavNode::moving(ctl, sc.obstacles, &sc.velocities, &params.frame_id)
        .with_context(|| format!("map {}", params.map))?;
    Ok(if params.lidar {
        nav.with_lidar(sc.lidar)
    } else {
        nav
    })
}
