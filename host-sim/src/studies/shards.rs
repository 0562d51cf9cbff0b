//! The shard bookkeeping that `merge` of a batch and of a robustness study
//! share: which shards the merged directories hold, each at most once, and
//! the errors of a merge that do not depend on the study.

use std::path::{Path, PathBuf};

/// Why directories do not merge, for either study.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// `merge` without directories.
    #[error("merge needs at least one {study} directory")]
    NoInputs {
        /// The study: "batch" or "robustness".
        study: &'static str,
    },
    /// A directory to merge is of another study than the first.
    #[error(
        "{}: not the same study as {} ({agree} must agree)",
        dir.display(),
        first.display()
    )]
    OtherStudy {
        /// The directory.
        dir: PathBuf,
        /// The first directory given.
        first: PathBuf,
        /// What defines the study, e.g. "family, seeds, ... and shard count".
        agree: &'static str,
    },
    /// A shard given twice.
    #[error("{}: shard {shard}/{count} given twice", dir.display())]
    ShardTwice {
        /// The directory.
        dir: PathBuf,
        /// The shard's index, from 1.
        shard: u32,
        /// The shard count.
        count: u32,
    },
}

/// The shards of `1..=count` not in `seen`, as `"s/count"`.
pub fn missing_shards(seen: &[u32], count: u32) -> Vec<String> {
    (1..=count)
        .filter(|s| !seen.contains(s))
        .map(|s| format!("{s}/{count}"))
        .collect()
}

/// Adds to `seen` the shards directory `dir` holds: its `merged` shards when
/// it is itself a merge, else its own `index` (of `count`). Fails on a shard
/// already in `seen`.
pub fn add_shards(
    seen: &mut Vec<u32>,
    dir: &Path,
    index: u32,
    merged: &[u32],
    count: u32,
) -> Result<(), MergeError> {
    let own = [index];
    let mine = if merged.is_empty() { &own[..] } else { merged };
    for &s in mine {
        if seen.contains(&s) {
            return Err(MergeError::ShardTwice {
                dir: dir.to_path_buf(),
                shard: s,
                count,
            });
        }
        seen.push(s);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shard_counts_once_and_the_missing_ones_are_named() {
        let mut seen = Vec::new();
        add_shards(&mut seen, Path::new("a"), 1, &[], 4).unwrap();
        add_shards(&mut seen, Path::new("b"), 0, &[3, 4], 4).unwrap();
        let err = add_shards(&mut seen, Path::new("c"), 3, &[], 4).unwrap_err();
        assert_eq!(err.to_string(), "c: shard 3/4 given twice");
        assert_eq!(missing_shards(&seen, 4), ["2/4"]);
    }

    #[test]
    fn the_merge_messages_name_the_study_and_the_directories() {
        let none = MergeError::NoInputs { study: "batch" };
        assert_eq!(none.to_string(), "merge needs at least one batch directory");
        let other = MergeError::OtherStudy {
            dir: "b".into(),
            first: "a".into(),
            agree: "family and seeds",
        };
        assert_eq!(
            other.to_string(),
            "b: not the same study as a (family and seeds must agree)"
        );
    }
}
