//! Why a batch could not run, be written, read back or merged ([`BatchError`]):
//! each error names the argument, the seed, or the directory or file (and
//! line, and field) concerned.

use std::path::PathBuf;

use super::{MAX_SEEDS, SeedRange, Shard};
use crate::scenario::ScenarioError;
use crate::sim::SimError;

/// Why a batch could not run, be written, read back or merged.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// `--jobs 0`.
    #[error("--jobs must be >= 1")]
    NoJobs,
    /// The seed range is larger than [`MAX_SEEDS`].
    #[error("seed range {0} holds more than {MAX_SEEDS} seeds")]
    TooManySeeds(SeedRange),
    /// The family's scenario (at the first seed) could not be loaded.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// The family's scenario has no `[generator]`.
    #[error(
        "scenario {name} ({file}) has no [generator]: a batch needs a seeded family (e.g. random)"
    )]
    NoGenerator {
        /// The scenario's name.
        name: String,
        /// Where it was read from.
        file: String,
    },
    /// The shard holds none of the seeds.
    #[error("shard {shard} of seeds {seeds} holds no seed (more shards than seeds)")]
    EmptyShard {
        /// The shard.
        shard: Shard,
        /// The study's seeds.
        seeds: SeedRange,
    },
    /// The output directory cannot be created (checked before the runs).
    #[error("--out {}", path.display())]
    Out {
        /// The `--out` path.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The worker thread pool could not be built.
    #[error("cannot start the worker threads")]
    Threads(#[source] rayon::ThreadPoolBuildError),
    /// The scenario of one seed could not be loaded.
    #[error("seed {seed}")]
    SeedScenario {
        /// The seed.
        seed: u64,
        /// Why.
        source: ScenarioError,
    },
    /// The simulation of one seed could not start or was cancelled.
    #[error("seed {seed}")]
    SeedRun {
        /// The seed.
        seed: u64,
        /// Why.
        source: SimError,
    },
    /// The output directory could not be written (nothing of it is left).
    #[error(transparent)]
    Write(#[from] crate::studies::output::WriteError),
    /// The summary could not be serialised.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// The path given to read is a file.
    #[error(
        "{}: is a file, not a batch directory (give the directory written by `batch` or `merge`)",
        dir.display()
    )]
    NotADirectory {
        /// The path given.
        dir: PathBuf,
    },
    /// The path given to read does not exist.
    #[error("{}: no such batch directory", dir.display())]
    NoDirectory {
        /// The path given.
        dir: PathBuf,
    },
    /// The path given to read cannot be examined.
    #[error("{}: {error}", dir.display())]
    Metadata {
        /// The path given.
        dir: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The directory lacks one of its files.
    #[error(
        "{}: not a batch directory (no {name}; give the directory written by `batch` or `merge`)",
        dir.display()
    )]
    Missing {
        /// The directory.
        dir: PathBuf,
        /// The missing file's name.
        name: String,
    },
    /// A file of the directory could not be read.
    #[error("{}: cannot read: {error}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// A file of the directory is not UTF-8 text.
    #[error("{}: not a text file (invalid UTF-8)", path.display())]
    NotText {
        /// The file.
        path: PathBuf,
    },
    /// A file of the directory is empty (or blank).
    #[error("{}: empty file", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// `summary.json` does not parse as a batch summary.
    #[error("{}: not a batch summary: {error}", path.display())]
    Summary {
        /// The file.
        path: PathBuf,
        /// Why.
        error: serde_json::Error,
    },
    /// `summary.json`'s field `meta.kind` is not a batch's.
    #[error("{}: field `meta.kind` is {kind:?}, not \"ldcbf-sim batch\"", path.display())]
    Kind {
        /// The file.
        path: PathBuf,
        /// The field's value.
        kind: String,
    },
    /// `runs.csv` has a foreign header (line 1).
    #[error(
        "{}:1: unexpected header (not a runs.csv written by ldcbf-sim batch)",
        path.display()
    )]
    Header {
        /// The file.
        path: PathBuf,
    },
    /// `runs.csv`'s last line has no newline.
    #[error(
        "{}:{line}: the last line ends without a newline (truncated file?)",
        path.display()
    )]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The last line's number, from 1.
        line: usize,
    },
    /// A row of `runs.csv` is malformed (the message names the field).
    #[error("{}:{line}: {error}", path.display())]
    Row {
        /// The file.
        path: PathBuf,
        /// The line's number, from 1.
        line: usize,
        /// What is wrong.
        error: String,
    },
    /// `runs.csv` holds another number of rows than `summary.json` says.
    #[error(
        "{}: {rows} rows but summary.json says {runs} runs (truncated file?)",
        path.display()
    )]
    RowCount {
        /// The file.
        path: PathBuf,
        /// Rows read.
        rows: usize,
        /// Field `meta.runs`.
        runs: usize,
    },
    /// `summary.json` names impossible shards: a merge's list holds 0, or a
    /// merge is not the whole study's shard `1/1`.
    #[error(
        "{}: field `meta.merged_shards`: {merged:?} with shard {shard} (a merge is shard 1/1 \
         and holds shards numbered from 1)",
        path.display()
    )]
    Shards {
        /// The file.
        path: PathBuf,
        /// Field `meta.shard`.
        shard: Shard,
        /// Field `meta.merged_shards`.
        merged: Vec<u32>,
    },
    /// A shard's `runs.csv` does not hold every seed of its shard.
    #[error(
        "{}: {rows} rows, but shard {shard} of seeds {seeds} has {own} seeds (a shard holds \
         every seed of its shard)",
        path.display()
    )]
    ShardSeeds {
        /// The file.
        path: PathBuf,
        /// Rows read.
        rows: usize,
        /// Field `meta.shard`.
        shard: Shard,
        /// Field `meta.seeds`.
        seeds: SeedRange,
        /// Seeds of the shard.
        own: u64,
    },
    /// The directories do not merge: none, of another study, or a shard
    /// twice.
    #[error(transparent)]
    Merge(#[from] crate::studies::shards::MergeError),
    /// A seed appears in two merged directories.
    #[error("seed {0} appears twice")]
    SeedTwice(u64),
    /// Seeds are missing and `--allow-partial` was not given.
    #[error(
        "incomplete study: {runs} of {expected} seeds (missing shards: {missing}); pass --allow-partial to merge anyway"
    )]
    Incomplete {
        /// Seeds merged.
        runs: usize,
        /// Seeds of the study.
        expected: u64,
        /// The missing shards (`k/n`, comma-separated), or why none is.
        missing: String,
    },
}
