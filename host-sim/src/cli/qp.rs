//! `ldcbf-sim qp solve`: dense QPs from npz files through our solver (and
//! Clarabel with `--check`), as CSV.

use anyhow::Result;

use super::args::QpSolveArgs;
use super::output::outln;
use crate::studies::qpbench::{CSV_HEADER, SolveOptions, solve_file};

/// Solves every file first (on any error nothing is printed but the error),
/// then prints the CSV header and one row per file.
pub(crate) fn solve(args: QpSolveArgs) -> Result<()> {
    let QpSolveArgs {
        files,
        repeat,
        max_iter,
        check,
    } = args;
    let opts = SolveOptions {
        repeat,
        max_iter,
        check,
    };
    let rows = files
        .iter()
        .map(|f| solve_file(f, &opts))
        .collect::<Result<Vec<_>, _>>()?;
    outln!("{CSV_HEADER}");
    for r in &rows {
        outln!("{}", r.csv());
    }
    Ok(())
}
