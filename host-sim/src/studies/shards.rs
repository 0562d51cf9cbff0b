//! The shard bookkeeping that `merge` of a batch and of a robustness study
//! share: which shards the merged directories hold, each at most once.

use std::path::{Path, PathBuf};

/// A shard given twice to `merge`.
#[derive(Debug, thiserror::Error)]
#[error("{}: shard {shard}/{count} given twice", dir.display())]
pub struct ShardTwice {
    /// The directory.
    pub dir: PathBuf,
    /// The shard's index, from 1.
    pub shard: u32,
    /// The shard count.
    pub count: u32,
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
) -> Result<(), ShardTwice> {
    let own = [index];
    let mine = if merged.is_empty() { &own[..] } else { merged };
    for &s in mine {
        if seen.contains(&s) {
            return Err(ShardTwice {
                dir: dir.to_path_buf(),
                shard: s,
                count,
            });
        }
        seen.push(s);
    }
    Ok(())
}
