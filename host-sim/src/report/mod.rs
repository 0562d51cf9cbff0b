//! Run outputs: the summary, the CSV logs, the output directory and the plots.
//!
//! Files written by [`write_logs`] (all CSV with a header line, SI units, world
//! frame):
//!
//! * `cycles.csv`: one row per control cycle: `t` (s), `time_in_step` (s),
//!   `step`, `stance`, `x0_px, x0_py, x0_vx, x0_vy, x0_theta` (the predicted state
//!   at the end of the current step), `active_obstacles`, `truncated`, `status`
//!   (`CycleStatus::name`), `source` (where the command came from), `iterations`,
//!   `active_set`, `compute_ns` (wall clock around the controller call only;
//!   with `run --repeat K` the minimum of K timings of the call on the same
//!   input and state, `SimOptions::timing_repeats`),
//!   `max_violation` (of this cycle's QP rows by the returned plan, in the rows'
//!   physical units: m/s for velocity rows, m for reachability rows, m of `h`
//!   for LDCBF rows), `cost` (m^2), `min_h0` (m), `relax_gait` (m/s of the
//!   bounded body-frame velocity component), `relax_safety` (m of the barrier
//!   `h`), `relax_capture` (m/s, the capturability bound) (the uniform
//!   relaxations of an infeasible cycle, see `ldcbf_controller::relax`),
//!   `foot_x, foot_y` (the swing target), `omega`
//!   (rad/s), `landed` (1 when this target is where the foot landed).
//! * `footsteps.csv`: `step, side, x, y, t, heading, clearance`: the initial
//!   stance foot is step 0; step `k` landed at the end of step `k - 1`;
//!   `heading` (rad) is the footprint's long axis, `clearance` (m) the
//!   footprint's signed clearance to the true obstacles.
//! * `trajectory.csv`: `t, px, py, vx, vy, theta, omega, stance, clearance` of the
//!   CoM, every `trajectory_every`-th 1 kHz plant sample (every sample with 1;
//!   the clearance minimum in the summary always uses every sample).
//! * `summary.json`: [`Summary`].
//! * `run.mcap`: the run for Foxglove ([`mcap`]).

//!
//! The figures of a run (map, state panels, LDCBF frames, LiDAR and planner
//! views, the animated GIF) are [`plot`]. The report room reads what the closed
//! loop ([`crate::sim`]) recorded; the studies and the command line use it.

mod logs;
mod mapping;
pub mod mcap;
mod output_file;
pub mod plot;
mod summary;
#[cfg(test)]
mod tests;

pub use logs::{OutputDir, write_logs};
pub use mapping::{MappingSummary, mapping_line, summarize_mapping};
pub use output_file::{check_output_file, write_output_file};
pub use summary::{
    ComputeStats, Summary, compute_stats, human_summary, nearest_rank, percentile, summarize,
};
