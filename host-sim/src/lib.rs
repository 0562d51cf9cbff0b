//! # ldcbf-sim
//!
//! The host simulator of ldcbf-nav (docs/maths.md §4): the closed loop in which the
//! `ldcbf-controller` footstep MPC walks a simulated linear inverted pendulum
//! through a scenario, the logs of the run, the figures, and the studies over
//! many runs.
//!
//! The crate is split into rooms, each with one job; a room uses only the rooms
//! below it (`tests/layering.rs` checks it, `docs/architecture.md` draws it):
//!
//! * [`world`]: polygons, the robot's body, the map's R-tree and occupancy
//!   grid, and the seeded map generators (the lowest room);
//! * [`sense`]: simulated 2D LiDAR, DBSCAN and one convex obstacle per
//!   cluster, for unknown maps (docs/maths.md §6), and its `[lidar]` settings;
//! * [`plan`]: RRT* on an occupancy grid of the known map, whose path gives
//!   the subgoals (docs/maths.md §5), and its `[rrt_star]` settings;
//! * [`plant`]: the continuous 3D-LIP integrated in closed form at 1 kHz, and
//!   its disturbances (the `[disturbance]` table);
//! * [`scenario`]: TOML scenario files, validation, `--set` overrides and the
//!   seeded `random` scenario; it reads the settings of the rooms below;
//! * [`sim`]: the closed loop (controller at 20 Hz or once per step, with the own
//!   QP solver or Clarabel) and the records it keeps;
//! * [`report`]: `cycles.csv`, `footsteps.csv`, `trajectory.csv`, `summary.json`,
//!   the atomic output directory, and the plots and animated GIF;
//! * [`studies`]: `batch`, `robustness`, `deadline`, `replay` and `qp solve`,
//!   many runs (or QPs) at once;
//! * [`cli`]: the command line of the `ldcbf-sim` binary (`src/main.rs` only
//!   calls [`cli::main`]): arguments, one function per subcommand, and the
//!   `run` pipeline.
//!
//! Frames and units: world frame W, metres, seconds, radians, as in the controller.

pub mod cli;
pub mod plan;
pub mod plant;
pub mod report;
pub mod scenario;
pub mod sense;
pub mod sim;
pub mod studies;
pub mod world;

pub use cli::app::{RunReport, RunRequest, execute_run};
pub use plant::{Plant, PlantParams};
pub use report::{Summary, summarize};
pub use scenario::{LoadOptions, Scenario, ScenarioError};
pub use sim::{MpcRate, Outcome, SimOptions, SimResult, Solver, run};
