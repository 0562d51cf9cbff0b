//! Why a robustness study could not run, be written, read back or merged
//! ([`RobustnessError`]): each error names the argument, the condition and
//! case, or the directory or file (and line, and field) concerned.

use std::path::PathBuf;

use super::KIND;
use crate::sim::SimError;
use crate::studies::batch::Shard;
use crate::studies::deadline::DeadlineError;

/// Why a robustness study could not run, be written, read back or merged.
#[derive(Debug, thiserror::Error)]
pub enum RobustnessError {
    /// `--jobs 0`.
    #[error("--jobs must be >= 1")]
    NoJobs,
    /// A margin (delta, m) is negative or not finite.
    #[error("every delta must be finite and >= 0")]
    Delta,
    /// `--shard` without `--out`.
    #[error("--shard {0} needs --out (merge reads the shard directories)")]
    ShardNeedsOut(Shard),
    /// The output directory cannot be created (checked before the runs).
    #[error("--out {}", path.display())]
    Out {
        /// The `--out` path.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A case's scenario could not be loaded under a condition.
    #[error("condition {disturbance} {magnitude}, delta {delta}")]
    Case {
        /// The condition's disturbance.
        disturbance: String,
        /// The condition's magnitude.
        magnitude: String,
        /// The margin, m.
        delta: f64,
        /// Why (names the case; boxed, it is large).
        source: Box<DeadlineError>,
    },
    /// The shard holds none of the study's runs.
    #[error("shard {shard} of a study of {runs} runs holds no run (more shards than runs)")]
    EmptyShard {
        /// The shard.
        shard: Shard,
        /// Runs of the whole study.
        runs: usize,
    },
    /// The worker thread pool could not be built.
    #[error("cannot start the worker threads")]
    Threads(#[source] rayon::ThreadPoolBuildError),
    /// A run's simulation could not start or was cancelled.
    #[error("{label}")]
    Run {
        /// The case's label.
        label: String,
        /// Why.
        source: SimError,
    },
    /// The output directory could not be written (nothing of it is left).
    #[error(transparent)]
    Write(#[from] crate::studies::output::WriteError),
    /// A file could not be read.
    #[error("{}: {error}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The summary could not be serialised.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// The path given to read is not a directory.
    #[error(
        "{}: no such robustness directory (give the directory written by `robustness --out` or `merge`)",
        dir.display()
    )]
    NoDirectory {
        /// The path given.
        dir: PathBuf,
    },
    /// `summary.json` does not parse as a robustness summary.
    #[error("{}: not a robustness summary: {error}", path.display())]
    Summary {
        /// The file.
        path: PathBuf,
        /// Why.
        error: serde_json::Error,
    },
    /// `summary.json`'s field `meta.kind` is not a robustness study's.
    #[error("{}: field `meta.kind` is {kind:?}, not {KIND:?}", path.display())]
    Kind {
        /// The file.
        path: PathBuf,
        /// The field's value.
        kind: String,
    },
    /// `summary.json`'s fields `shard`, `shard_count`, `merged_shards`
    /// contradict each other.
    #[error(
        "{}: inconsistent shard fields (shard {shard}, shard_count {shard_count}, merged_shards {merged_shards:?})",
        path.display()
    )]
    ShardFields {
        /// The file.
        path: PathBuf,
        /// Field `shard`.
        shard: Shard,
        /// Field `shard_count`.
        shard_count: u32,
        /// Field `merged_shards`.
        merged_shards: Vec<u32>,
    },
    /// `summary.json`'s field `study_runs` is not the study's size.
    #[error("{}: study_runs {study_runs} does not match the study it describes", path.display())]
    StudyRuns {
        /// The file.
        path: PathBuf,
        /// Field `study_runs`.
        study_runs: usize,
    },
    /// `runs.csv` has a foreign header (line 1).
    #[error(
        "{}:1: unexpected header (not a runs.csv written by ldcbf-sim robustness)",
        path.display()
    )]
    Header {
        /// The file.
        path: PathBuf,
    },
    /// `runs.csv` holds another number of rows than `summary.json` says.
    #[error(
        "{}: {rows} rows but summary.json says {runs} runs of shard {shard} (truncated file?)",
        path.display()
    )]
    RowCount {
        /// The file.
        path: PathBuf,
        /// Rows read.
        rows: usize,
        /// Field `runs`.
        runs: usize,
        /// Field `shard`.
        shard: Shard,
    },
    /// A row of `runs.csv` is malformed or not the study's run at its place
    /// (the message names the field).
    #[error("{}:{line}: {error}", path.display())]
    Row {
        /// The file.
        path: PathBuf,
        /// The line's number, from 1.
        line: usize,
        /// What is wrong.
        error: String,
    },
    /// The directories do not merge: none, of another study, or a shard
    /// twice.
    #[error(transparent)]
    Merge(#[from] crate::studies::shards::MergeError),
    /// Shards are missing and `--allow-partial` was not given.
    #[error(
        "incomplete study: {runs} of {expected} runs (missing shards: {missing}); pass --allow-partial to merge anyway"
    )]
    Incomplete {
        /// Runs merged.
        runs: usize,
        /// Runs of the study.
        expected: usize,
        /// The missing shards (`k/n`, comma-separated).
        missing: String,
    },
}
