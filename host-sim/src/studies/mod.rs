//! Studies over many runs (or QPs), each behind one `ldcbf-sim` command:
//!
//! * [`batch`]: `ldcbf-sim batch` and `merge`: many seeds of a scenario family in
//!   parallel, sharded across machines, one CSV row per run and a Markdown table;
//! * [`robustness`]: `ldcbf-sim robustness`: success and true CoM clearance
//!   under each disturbance, with and without the safety margin `delta`;
//! * [`crowdnav`]: `ldcbf-sim crowdnav`: the crowd-navigation benchmark
//!   (CrowdNav's circle and square crossing), our controller and an ORCA robot;
//! * [`deadline`]: `ldcbf-sim deadline`: per-cycle compute time, solver
//!   iterations and (from the firmware) instructions against a real-time deadline;
//! * [`replay`]: a run's controller inputs rebuilt from its logs, to replay its
//!   cycles outside the loop (benchmarks);
//! * [`qpbench`]: `ldcbf-sim qp solve`, our solver on npz QP files, timed.
//!
//! Uses the rooms below it (scenario, sim, report); only [`crate::cli`] uses it.

pub mod batch;
pub mod crowdnav;
pub mod deadline;
pub mod output;
pub mod qpbench;
pub mod replay;
pub mod robustness;
pub mod shards;
