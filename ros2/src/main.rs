//! `ldcbf-ros2`: the ldcbf-nav footstep planner as a ROS 2 node (docs/ros2.md).
//!
//! ```text
//! ldcbf-ros2 [--params FILE] [--idle-exit S]    the node
//! ldcbf-ros2 robot [--params FILE]              the robot stand-in (the map's scenario)
//! ldcbf-ros2 record SCENARIO FILE [--set k=v]   a run's inputs as messages (JSON)
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use ldcbf_ros2::params::Params;

#[derive(Parser)]
#[command(
    name = "ldcbf-ros2",
    about = "ldcbf-nav footstep planner as a ROS 2 node"
)]
struct Cli {
    /// Parameter file (ROS 2 layout, `ldcbf_nav: ros__parameters: ...`).
    #[arg(long, global = true)]
    params: Option<PathBuf>,
    /// Stop after S seconds without an input message (default: run forever).
    #[arg(long, value_name = "S")]
    idle_exit: Option<f64>,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// The robot stand-in: the simulator's plant at the start of the map's
    /// scenario, publishing /odom, /gait_state and /goal_pose and walking on
    /// the node's commands until the goal or the time limit.
    Robot,
    /// Simulate SCENARIO (no planner) and write its inputs as ROS 2 messages
    /// with the node's commands to FILE (JSON): the DDS test's data.
    Record {
        /// Scenario name or path.
        scenario: String,
        /// Output JSON file (written atomically; an existing file is
        /// replaced only if it is an earlier recording).
        file: PathBuf,
        /// Scenario overrides, as `ldcbf-sim run --set`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
    },
}

/// Whether the file at `p` is an earlier `record` output (it may be
/// replaced): it begins as [`ldcbf_ros2::record::Played`]'s JSON does.
fn is_recording(p: &std::path::Path) -> bool {
    use std::io::Read as _;
    const HEAD: &[u8] = b"{\"scenario\":";
    let mut head = [0u8; HEAD.len()];
    std::fs::File::open(p).is_ok_and(|mut f| f.read_exact(&mut head).is_ok() && head == HEAD)
}

fn params(cli: &Cli) -> Result<Params> {
    match &cli.params {
        Some(p) => Params::load(p),
        None => Ok(Params::default()),
    }
}

fn main_result(cli: Cli) -> Result<()> {
    let params = params(&cli)?;
    match cli.command {
        None => {
            let idle = match cli.idle_exit {
                Some(s) if s.is_finite() && s > 0.0 => Some(Duration::from_secs_f64(s)),
                Some(s) => anyhow::bail!("--idle-exit: expected seconds > 0, got {s}"),
                None => None,
            };
            let nav = ldcbf_ros2::nav_node(&params)?;
            eprintln!(
                "ldcbf-ros2: node {} on domain {}{}, map {}",
                ldcbf_ros2::params::NODE_NAME,
                params.domain_id,
                if params.localhost_only {
                    " (localhost only)"
                } else {
                    ""
                },
                params.map
            );
            let n = ldcbf_ros2::dds::spin(&params, nav, idle)?;
            eprintln!("ldcbf-ros2: {n} cycles");
        }
        Some(Command::Robot) => {
            let sc = ldcbf_sim::scenario::load(
                &params.map,
                &ldcbf_sim::scenario::LoadOptions {
                    seed: None,
                    sets: params.sets.clone(),
                },
            )
            .with_context(|| format!("map {}", params.map))?;
            let robot = ldcbf_ros2::robot::Robot::new(&sc, &params.frame_id)?;
            let (end, cycles) = ldcbf_ros2::dds::run_robot(
                &params,
                robot,
                Duration::from_millis(500),
                Duration::from_secs(30),
            )?;
            println!("ldcbf-ros2 robot: {end:?} after {cycles} cycles");
        }
        Some(Command::Record {
            scenario,
            file,
            sets,
        }) => {
            let mut kv = Vec::new();
            for s in &sets {
                let (k, v) = s
                    .split_once('=')
                    .with_context(|| format!("--set {s}: expected KEY=VALUE"))?;
                kv.push((k.to_string(), v.to_string()));
            }
            ldcbf_sim::report::check_output_file(&file, is_recording)
                .with_context(|| format!("{}", file.display()))?;
            let played = ldcbf_ros2::record::play(&scenario, &kv, &params.frame_id)?;
            let text = serde_json::to_string(&played)?;
            ldcbf_sim::report::write_output_file(&file, &text, is_recording)
                .with_context(|| format!("{}", file.display()))?;
            println!(
                "{}: {} cycles ({} equal to the run's command bit for bit)",
                file.display(),
                played.cycles.len(),
                played.same_as_run
            );
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    match main_result(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ldcbf-ros2: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
