//! # ldcbf-sim
//!
//! The host simulator of ldcbf-nav (SPEC section 4): the closed loop in which the
//! `ldcbf-controller` footstep MPC walks a simulated linear inverted pendulum
//! through a scenario, the logs of the run, and the figures.
//!
//! * [`plant`]: the continuous 3D-LIP integrated in closed form at 1 kHz;
//! * [`scenario`]: TOML scenario files, validation, `--set` overrides and the
//!   seeded `random` family;
//! * [`planner`]: RRT* on an occupancy grid of the known map, whose path gives
//!   the subgoals (SPEC 5);
//! * [`perception`]: simulated 2D LiDAR, DBSCAN and one convex obstacle per
//!   cluster, for unknown maps (SPEC 6);
//! * [`obstacle_index`]: the known map's R-tree, so that a control cycle's
//!   cost does not grow with the map;
//! * [`families`]: seeded layout families for a robot with a body (corridors,
//!   doorways, cups, wall starts, clutter, thin walls);
//! * [`robot`]: the robot's body disk and footprint (the `[robot]` table);
//! * [`disturbance`]: pushes, CoM height mismatch, foot placement error and
//!   state estimation noise (the `[disturbance]` table);
//! * [`sim`]: the closed loop (controller at 20 Hz or once per step, with the own
//!   QP solver or Clarabel);
//! * [`report`]: `cycles.csv`, `footsteps.csv`, `trajectory.csv`, `summary.json`
//!   and the atomic output directory;
//! * [`plot`]: the map, state panels, LDCBF frames and the animated GIF, drawn
//!   with plotters and an embedded font (no system font needed);
//! * [`app`]: the `run` pipeline behind the `ldcbf-sim` binary;
//! * [`qpbench`]: `ldcbf-sim qp solve`, our solver on npz QP files, timed;
//! * [`batch`]: `ldcbf-sim batch` and `merge`: many seeds of a scenario family in
//!   parallel, sharded across machines, one CSV row per run and a Markdown table;
//! * [`robustness`]: `ldcbf-sim robustness`: success and true CoM clearance
//!   under each disturbance, with and without the safety margin `delta`;
//! * [`deadline`]: `ldcbf-sim deadline`: per-cycle compute time, solver
//!   iterations and (from the firmware) instructions against a real-time deadline;
//! * [`replay`]: a run's controller inputs rebuilt from its logs, to replay its
//!   cycles outside the loop (benchmarks).
//!
//! Frames and units: world frame W, metres, seconds, radians, as in the controller.

pub mod app;
pub mod batch;
pub mod deadline;
pub mod disturbance;
pub mod families;
pub mod obstacle_index;
pub mod perception;
pub mod planner;
pub mod plant;
pub mod plot;
pub mod qpbench;
pub mod replay;
pub mod report;
pub mod robot;
pub mod robustness;
pub mod scenario;
pub mod sim;

pub use app::{RunReport, RunRequest, execute_run};
pub use plant::{Plant, PlantParams};
pub use report::{Summary, summarize};
pub use scenario::{LoadOptions, Scenario, ScenarioError};
pub use sim::{MpcRate, Outcome, SimOptions, SimResult, Solver, run};
