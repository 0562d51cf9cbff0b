//! `ldcbf-sim run` (one scenario, through the [`super::app`] pipeline) and
//! `ldcbf-sim list` (the shipped scenarios).

use anyhow::Result;

use super::app::{RunRequest, execute_run};
use super::args::{LoopArgs, RunArgs};
use super::output::{out, outln};

/// Simulates the scenario, writes its output directory and prints the human
/// summary and what was written.
pub(crate) fn run(args: RunArgs) -> Result<()> {
    let RunArgs {
        scenario,
        out,
        seed,
        closed_loop:
            LoopArgs {
                sets,
                solver,
                mpc_rate,
            },
        no_plots,
        no_gif,
        no_mcap,
        trajectory_every,
        export_qps,
        repeat,
    } = args;
    let req = RunRequest {
        out,
        seed,
        sets,
        solver,
        mpc_rate,
        plots: !no_plots,
        gif: !no_gif,
        mcap: !no_mcap,
        trajectory_every,
        export_qps: export_qps.clone(),
        timing_repeats: repeat,
        ..RunRequest::new(&scenario)
    };
    let rep = execute_run(&req)?;
    for w in &rep.warnings {
        outln!("warning: {w}");
    }
    out!("{}", crate::report::human_summary(&rep.summary));
    outln!("wrote {}/: {}", rep.out_dir.display(), rep.files.join(" "));
    if let Some(d) = export_qps {
        outln!("wrote {} QPs to {}/", rep.result.qps.len(), d.display());
    }
    Ok(())
}

/// Prints the scenario folder and one line per shipped scenario.
pub(crate) fn list() -> Result<()> {
    let dir = crate::scenario::scenario_dir();
    outln!("scenarios in {}:", dir.display());
    for (name, desc, _) in crate::scenario::list() {
        outln!("  {name:<10} {desc}");
    }
    Ok(())
}
