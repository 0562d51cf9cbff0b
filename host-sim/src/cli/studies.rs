//! `ldcbf-sim deadline` (compute time and iterations per cycle against a
//! deadline) and `ldcbf-sim robustness` (disturbances and safety margins).

use anyhow::Result;

use super::args::{
    CrowdNavArgs, CrowdNavLayoutArg, CrowdNavPerception, DeadlineArgs, RobustnessArgs, capped_jobs,
};
use super::output::{out, outln};
use crate::studies::deadline::{self, DeadlineRequest};
use crate::studies::robustness::{self, RobustnessRequest};

/// Runs the deadline study and prints its Markdown table.
pub(crate) fn deadline(args: DeadlineArgs) -> Result<()> {
    let DeadlineArgs {
        cases,
        random,
        deadline_us,
        clock_mhz,
        sets,
        jobs,
        repeat,
        instructions,
    } = args;
    let mut req = DeadlineRequest::new();
    if !cases.is_empty() {
        req.cases = cases;
    }
    req.random = random;
    req.deadline_us = deadline_us;
    req.clock_mhz = clock_mhz;
    req.sets = sets;
    req.jobs = capped_jobs(jobs);
    req.repeat = repeat;
    req.instructions = instructions;
    out!("{}", deadline::markdown(&deadline::run_deadline(&req)?));
    Ok(())
}

/// Runs the robustness study (or one shard of it) and prints its Markdown
/// tables.
pub(crate) fn robustness(args: RobustnessArgs) -> Result<()> {
    let RobustnessArgs {
        cases,
        random,
        deltas,
        sets,
        jobs,
        out,
        shard,
        quiet,
    } = args;
    let mut req = RobustnessRequest::new();
    req.shard = shard;
    if !cases.is_empty() {
        req.cases = cases;
    }
    req.random = random;
    req.deltas = deltas;
    req.sets = sets;
    if let Some(j) = jobs {
        req.jobs = capped_jobs(j);
    }
    req.out = out;
    req.progress = !quiet;
    out!(
        "{}",
        robustness::markdown(&robustness::run_robustness(&req)?)
    );
    Ok(())
}

/// Runs the crowd-navigation benchmark and prints its Markdown row (with
/// `--out`, also the cases' CSV and the table, written at once).
pub(crate) fn crowdnav(args: CrowdNavArgs) -> Result<()> {
    use crate::studies::crowdnav::{
        CrowdNavRequest, TABLE_HEADER, csv, run_crowdnav, summarize, table_row,
    };
    use crate::world::crowd::families::CrowdNavLayout;
    let req = CrowdNavRequest {
        layout: match args.layout {
            CrowdNavLayoutArg::Circle => CrowdNavLayout::Circle,
            CrowdNavLayoutArg::Square => CrowdNavLayout::Square,
        },
        humans: args.humans as usize,
        cases: args.cases.start..args.cases.end,
        robot_visible: args.robot_visible,
        perception: match args.perception {
            CrowdNavPerception::Oracle => crate::sense::Perception::Known,
            CrowdNavPerception::Lidar => crate::sense::Perception::Lidar,
        },
        robot: args.robot,
        jobs: capped_jobs(
            args.jobs
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        ),
    };
    let rows = run_crowdnav(&req)?;
    let row = table_row(&req, &summarize(&rows));
    if let Some(dir) = &args.out {
        crate::studies::output::write_files(
            dir,
            &[
                ("cases.csv", csv(&rows)),
                ("table.md", format!("{TABLE_HEADER}\n{row}\n")),
            ],
        )?;
    }
    if args.header {
        outln!("{TABLE_HEADER}");
    }
    outln!("{row}");
    Ok(())
}
