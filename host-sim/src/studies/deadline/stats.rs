//! The per-cycle cost of a group of runs (worst cases, percentiles, cycles
//! over the deadline) and the firmware's instruction counts.

use super::*;

/// Where a worst case occurred.
#[derive(Clone, Debug, PartialEq)]
pub struct Worst {
    /// The value (iterations).
    pub value: u32,
    /// The run's label.
    pub label: String,
    /// The cycle's index in its run.
    pub cycle: usize,
    /// The cycle's simulated time, s.
    pub time: f64,
    /// The cycle's status.
    pub status: CycleStatus,
}

impl core::fmt::Display for Worst {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} in {} cycle {} (t = {:.2} s, {})",
            self.value,
            self.label,
            self.cycle,
            self.time,
            self.status.name()
        )
    }
}

/// The cycle with the longest compute time of a group of runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Slowest {
    /// Its compute time, ns ([`CycleCost::compute_ns`]).
    pub compute_ns: u64,
    /// The run's label.
    pub label: String,
    /// The cycle's index in its run, from 0 (data row `cycle + 1` of the
    /// `cycles.csv` that `ldcbf-sim run` writes).
    pub cycle: usize,
    /// The cycle's simulated time, s.
    pub time: f64,
    /// The cycle's status.
    pub status: CycleStatus,
    /// Its solver iterations.
    pub iterations: u32,
}

impl core::fmt::Display for Slowest {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} cycle {} (t = {:.2} s, {}, {} it)",
            self.label,
            self.cycle,
            self.time,
            self.status.name(),
            self.iterations
        )
    }
}

/// The per-cycle cost of a group of runs.
#[derive(Clone, Debug, PartialEq)]
pub struct CostStats {
    /// Runs.
    pub runs: usize,
    /// Control cycles.
    pub cycles: usize,
    /// Cycles whose nominal QP was not solved (status not `optimal`).
    pub non_optimal: usize,
    /// Of those, `budget_exhausted`.
    pub budget_exhausted: usize,
    /// Of those, `numerical_failure`.
    pub numerical_failure: usize,
    /// Of those, `invalid_input` (the run diverged).
    pub invalid_input: usize,
    /// Cycles whose command is a fallback ([`CycleCost::is_fallback`]).
    pub fallback: usize,
    /// Compute time per cycle, pooled over the group's cycles (nearest rank).
    pub compute: ComputeStats,
    /// Compute time of the non-optimal cycles only (the priority scheme's path).
    pub compute_non_optimal: ComputeStats,
    /// Cycles whose compute time exceeded the deadline.
    pub over_deadline: usize,
    /// The cycle of `compute.max_ns` (the first one on ties), if any.
    pub slowest: Option<Slowest>,
    /// Most iterations of an `optimal` cycle (one QP solve), if any.
    pub worst_optimal: Option<Worst>,
    /// Most iterations of any cycle (the priority scheme included), if any.
    pub worst_all: Option<Worst>,
    /// Smallest configured `max_iter` over the runs.
    pub max_iter: u32,
    /// Smallest configured `max_iter_cycle` over the runs.
    pub max_iter_cycle: u32,
    /// Runs that reached the goal.
    pub reached: usize,
}

fn worst_of<'a>(
    runs: &[&'a CaseRun],
    keep: impl Fn(&CycleCost) -> bool,
) -> Option<(&'a CaseRun, &'a CycleCost)> {
    let mut best: Option<(&CaseRun, &CycleCost)> = None;
    for r in runs {
        for c in r.cycles.iter().filter(|c| keep(c)) {
            // First occurrence on ties (runs in order, cycles in order).
            if best.is_none_or(|(_, b)| c.iterations > b.iterations) {
                best = Some((r, c));
            }
        }
    }
    best
}

fn slowest(runs: &[&CaseRun]) -> Option<Slowest> {
    let mut best: Option<(&CaseRun, &CycleCost)> = None;
    for r in runs {
        for c in &r.cycles {
            if best.is_none_or(|(_, b)| c.compute_ns > b.compute_ns) {
                best = Some((r, c));
            }
        }
    }
    best.map(|(r, c)| Slowest {
        compute_ns: c.compute_ns,
        label: r.label.clone(),
        cycle: c.index,
        time: c.time,
        status: c.status,
        iterations: c.iterations,
    })
}

/// The statistics of a group of runs; `deadline_ns` counts the cycles over it.
pub fn cost_stats(runs: &[&CaseRun], deadline_ns: u64) -> CostStats {
    let all = || runs.iter().flat_map(|r| r.cycles.iter());
    let count = |f: &dyn Fn(&CycleCost) -> bool| all().filter(|c| f(c)).count();
    let ns: Vec<u64> = all().map(|c| c.compute_ns).collect();
    let worst = |keep: &dyn Fn(&CycleCost) -> bool| {
        worst_of(runs, keep).map(|(r, c)| Worst {
            value: c.iterations,
            label: r.label.clone(),
            cycle: c.index,
            time: c.time,
            status: c.status,
        })
    };
    CostStats {
        runs: runs.len(),
        cycles: ns.len(),
        non_optimal: count(&|c| !c.status.is_optimal()),
        budget_exhausted: count(&|c| c.status == CycleStatus::BudgetExhausted),
        numerical_failure: count(&|c| c.status == CycleStatus::NumericalFailure),
        invalid_input: count(&|c| matches!(c.status, CycleStatus::InvalidInput(_))),
        fallback: count(&|c| c.is_fallback()),
        compute: compute_stats(&ns),
        compute_non_optimal: compute_stats(
            &all()
                .filter(|c| !c.status.is_optimal())
                .map(|c| c.compute_ns)
                .collect::<Vec<_>>(),
        ),
        over_deadline: count(&|c| c.compute_ns > deadline_ns),
        slowest: slowest(runs),
        worst_optimal: worst(&|c| c.status.is_optimal()),
        worst_all: worst(&|_| true),
        max_iter: runs.iter().map(|r| r.max_iter).min().unwrap_or(0),
        max_iter_cycle: runs.iter().map(|r| r.max_iter_cycle).min().unwrap_or(0),
        reached: runs
            .iter()
            .filter(|r| r.outcome == Outcome::GoalReached)
            .count(),
    }
}

/// The firmware's instruction counts per cycle (a CSV with
/// [`INSTRUCTIONS_HEADER`]), summarised.
#[derive(Clone, Debug, PartialEq)]
pub struct FirmwareInstructions {
    /// The file read.
    pub source: PathBuf,
    /// Cycles in it.
    pub cycles: usize,
    /// Cycles whose status was not `optimal`.
    pub non_optimal: usize,
    /// Most instructions of an `optimal` cycle, if any.
    pub max_optimal: Option<u64>,
    /// Most instructions of any cycle.
    pub max_all: u64,
    /// The cycle of `max_all` (the file's `cycle` column; the first on ties).
    pub max_all_cycle: u64,
    /// Its status, as written in the file.
    pub max_all_status: String,
    /// Most iterations of an `optimal` cycle, if any.
    pub iterations_optimal: Option<u32>,
    /// Most iterations of any cycle.
    pub iterations_all: u32,
}

/// Why a per-cycle instruction CSV could not be read: each names the file
/// (and the line where there is one).
#[derive(Debug, thiserror::Error)]
pub enum InstructionsError {
    /// The path is a directory.
    #[error("{}: is a directory, not an instruction CSV (firmware/target/instructions.csv)", path.display())]
    Directory {
        /// The path given.
        path: PathBuf,
    },
    /// The file could not be read.
    #[error("{}: cannot read the instruction counts", path.display())]
    Read {
        /// The path given.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not UTF-8 text.
    #[error("{}: not a text file (invalid UTF-8), expected the instruction CSV", path.display())]
    NotText {
        /// The path given.
        path: PathBuf,
    },
    /// The file is empty (or blank).
    #[error("{}: empty file, expected the header {INSTRUCTIONS_HEADER:?}", path.display())]
    Empty {
        /// The path given.
        path: PathBuf,
    },
    /// The last line has no newline.
    #[error("{}:{line}: the last line ends without a newline (truncated file?)", path.display())]
    Truncated {
        /// The path given.
        path: PathBuf,
        /// The last line's number (from 1).
        line: usize,
    },
    /// The first line is not [`INSTRUCTIONS_HEADER`].
    #[error("{}:1: expected the header {INSTRUCTIONS_HEADER:?} (written by tests/firmware_qemu.rs), got {header:?}", path.display())]
    Header {
        /// The path given.
        path: PathBuf,
        /// The first line, trimmed.
        header: String,
    },
    /// A data row is malformed.
    #[error("{}:{line}: {problem} in {text:?}", path.display())]
    Row {
        /// The path given.
        path: PathBuf,
        /// The row's line number (from 1).
        line: usize,
        /// What is wrong: a field count, or which field does not parse.
        problem: &'static str,
        /// The row as read.
        text: String,
    },
    /// The file has a header and no data row.
    #[error("{}: no cycles", path.display())]
    NoCycles {
        /// The path given.
        path: PathBuf,
    },
}

/// Reads a per-cycle instruction CSV ([`INSTRUCTIONS_HEADER`], as written by
/// `tests/firmware_qemu.rs`). Any malformed line is an error naming the file
/// and line.
pub fn read_instructions(path: &Path) -> Result<FirmwareInstructions, InstructionsError> {
    let path_buf = || path.to_path_buf();
    if path.is_dir() {
        return Err(InstructionsError::Directory { path: path_buf() });
    }
    let bytes =
        crate::scenario::limits::read_regular_file(path, crate::scenario::limits::MAX_FILE_BYTES)
            .map_err(|source| InstructionsError::Read {
            path: path_buf(),
            source,
        })?;
    let text =
        String::from_utf8(bytes).map_err(|_| InstructionsError::NotText { path: path_buf() })?;
    if text.trim().is_empty() {
        return Err(InstructionsError::Empty { path: path_buf() });
    }
    if !text.ends_with('\n') {
        return Err(InstructionsError::Truncated {
            path: path_buf(),
            line: text.lines().count(),
        });
    }
    let mut lines = text.lines();
    let header = lines.next().unwrap_or("").trim();
    if header != INSTRUCTIONS_HEADER {
        return Err(InstructionsError::Header {
            path: path_buf(),
            header: header.to_string(),
        });
    }
    let mut out = FirmwareInstructions {
        source: path.to_path_buf(),
        cycles: 0,
        non_optimal: 0,
        max_optimal: None,
        max_all: 0,
        max_all_cycle: 0,
        max_all_status: String::new(),
        iterations_optimal: None,
        iterations_all: 0,
    };
    for (i, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let bad = |problem: &'static str| InstructionsError::Row {
            path: path_buf(),
            line: i + 2,
            problem,
            text: line.to_string(),
        };
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 4 {
            return Err(bad("expected 4 fields"));
        }
        let cycle: u64 = f[0].parse().map_err(|_| bad("bad cycle"))?;
        let iterations: u32 = f[2].parse().map_err(|_| bad("bad iterations"))?;
        let instructions: u64 = f[3].parse().map_err(|_| bad("bad instructions"))?;
        if out.cycles == 0 || instructions > out.max_all {
            out.max_all = instructions;
            out.max_all_cycle = cycle;
            out.max_all_status = f[1].to_string();
        }
        out.cycles += 1;
        out.iterations_all = out.iterations_all.max(iterations);
        if f[1] == "optimal" {
            out.max_optimal = Some(out.max_optimal.unwrap_or(0).max(instructions));
            out.iterations_optimal = Some(out.iterations_optimal.unwrap_or(0).max(iterations));
        } else {
            out.non_optimal += 1;
        }
    }
    if out.cycles == 0 {
        return Err(InstructionsError::NoCycles { path: path_buf() });
    }
    Ok(out)
}
