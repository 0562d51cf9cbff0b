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

/// Checks the directories of a merge, read into `parts` (one per `inputs`
/// entry, same order): at least one, each of the first one's study (`head`
/// gives a part's study key, shard index, merged shards and shard count; a
/// mismatch names `agree`, what defines the `study`), no shard twice.
/// Returns the shards they hold, sorted.
pub fn merged_shards<T, K: PartialEq>(
    study: &'static str,
    agree: &'static str,
    inputs: &[PathBuf],
    parts: &[T],
    head: impl Fn(&T) -> (K, u32, &[u32], u32),
) -> Result<Vec<u32>, MergeError> {
    let (Some(first), Some(first_dir)) = (parts.first(), inputs.first()) else {
        return Err(MergeError::NoInputs { study });
    };
    let key = head(first).0;
    let mut shards = Vec::new();
    for (part, dir) in parts.iter().zip(inputs) {
        let (k, index, merged, count) = head(part);
        if k != key {
            return Err(MergeError::OtherStudy {
                dir: dir.clone(),
                first: first_dir.clone(),
                agree,
            });
        }
        add_shards(&mut shards, dir, index, merged, count)?;
    }
    shards.sort_unstable();
    Ok(shards)
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
fn add_shards(
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
    fn a_merge_needs_one_study_and_each_shard_once() {
        let dirs: Vec<PathBuf> = ["a", "b", "c"].iter().map(PathBuf::from).collect();
        // (study key, shard index, merged shards)
        let parts = [(1, 2, vec![]), (1, 0, vec![3, 1]), (1, 4, vec![])];
        fn head(p: &(i32, u32, Vec<u32>)) -> (i32, u32, &[u32], u32) {
            (p.0, p.1, &p.2[..], 4)
        }
        let all = merged_shards("batch", "the key", &dirs, &parts, head).unwrap();
        assert_eq!(all, [1, 2, 3, 4]);
        let none = merged_shards("batch", "the key", &[], &parts[..0], head);
        assert!(matches!(none, Err(MergeError::NoInputs { study: "batch" })));
        let other = [(1, 1, vec![]), (2, 2, vec![])];
        let err = merged_shards("batch", "the key", &dirs[..2], &other, head).unwrap_err();
        assert_eq!(
            err.to_string(),
            "b: not the same study as a (the key must agree)"
        );
        let twice = [(1, 1, vec![]), (1, 0, vec![2, 1])];
        let err = merged_shards("batch", "the key", &dirs[..2], &twice, head).unwrap_err();
        assert_eq!(err.to_string(), "b: shard 1/4 given twice");
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
