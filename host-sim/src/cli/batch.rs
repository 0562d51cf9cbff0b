//! `ldcbf-sim batch` (many seeds of a family), `merge` (shard directories of a
//! batch or robustness study) and `table` (batch directories side by side).

use anyhow::Result;

use super::args::{BatchArgs, LoopArgs, MergeArgs, TableArgs, capped_jobs};
use super::output::{out, outln};
use crate::studies::batch::{self, BatchReport, BatchRequest};
use crate::studies::robustness;

/// Runs the batch and prints its one-line summary.
pub(crate) fn batch(args: BatchArgs) -> Result<()> {
    let BatchArgs {
        family,
        seeds,
        planner,
        perception,
        jobs,
        shard,
        out,
        closed_loop:
            LoopArgs {
                sets,
                solver,
                mpc_rate,
            },
        quiet,
    } = args;
    let mut req = BatchRequest::new(&family, seeds);
    req.planner = planner;
    req.perception = perception;
    if let Some(j) = jobs {
        req.jobs = capped_jobs(j);
    }
    req.shard = shard;
    req.out = out;
    req.sets = sets;
    req.solver = solver;
    req.mpc_rate = mpc_rate;
    req.progress = !quiet;
    print_batch(&batch::run_batch(&req)?);
    Ok(())
}

/// Merges the shards of a robustness study (told by its first directory) or
/// of a batch, and prints the merged table or summary.
pub(crate) fn merge(args: MergeArgs) -> Result<()> {
    let MergeArgs {
        dirs,
        out,
        allow_partial,
    } = args;
    if robustness::is_robustness_dir(&dirs[0]) {
        let rep = robustness::merge(&dirs, &out, allow_partial)?;
        out!("{}", robustness::markdown(&rep));
        outln!("wrote {}/: runs.csv summary.json table.md", out.display());
    } else {
        print_batch(&batch::merge(&dirs, &out, allow_partial)?);
    }
    Ok(())
}

/// Prints the Markdown table of the batch directories, one column each (all
/// read before anything is printed).
pub(crate) fn table(args: TableArgs) -> Result<()> {
    let mut cols = Vec::new();
    for d in &args.dirs {
        let (meta, agg, _) = batch::read_dir(d)?;
        cols.push((batch::label(&meta), agg));
    }
    out!("{}", batch::markdown_table(&cols));
    Ok(())
}

/// The summary line of a batch and the files it wrote.
fn print_batch(rep: &BatchReport) {
    let a = &rep.aggregate;
    outln!(
        "{} seeds {} shard {}: {} runs, {} successful, {} collisions, {} stuck, {} time limit, {} diverged; wall time {:.1} s",
        rep.meta.scenario,
        rep.meta.seeds,
        rep.meta.shard,
        a.runs,
        a.success,
        a.collisions,
        a.stuck,
        a.timeouts,
        a.diverged,
        rep.meta.wall_time_s
    );
    outln!(
        "wrote {}/: runs.csv summary.json summary.md",
        rep.out_dir.display()
    );
}
