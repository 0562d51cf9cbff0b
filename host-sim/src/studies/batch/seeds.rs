//! What a study runs and where: seed ranges (`--seeds A..B`), shards
//! (`--shard I/N`) and the cap on worker threads (`--jobs`).

use serde::{Deserialize, Serialize};

/// Most seeds in one range (`batch --seeds`, `deadline` and `robustness
/// --random N`): 1,000,000 runs are days of computing; a study that big is
/// split into ranges or shards. A larger range is refused when parsed, before
/// anything is allocated for it.
pub const MAX_SEEDS: u64 = 1_000_000;

/// Most worker threads per core that `--jobs` may start ([`cap_jobs`]).
pub const JOBS_PER_CORE: usize = 4;

/// `requested` worker threads capped at [`JOBS_PER_CORE`] times the cores of
/// this machine; the second value is the note to print when it was lowered.
/// (Each run is compute-bound: more threads than cores only share them.)
pub fn cap_jobs(requested: usize) -> (usize, Option<String>) {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let max = cores * JOBS_PER_CORE;
    if requested > max {
        (
            max,
            Some(format!(
                "--jobs {requested} lowered to {max} ({JOBS_PER_CORE} per core, {cores} cores)"
            )),
        )
    } else {
        (requested, None)
    }
}

/// A half-open range of seeds `start..end`. Read from a file, it is checked
/// as when parsed from `--seeds` (not empty, at most [`MAX_SEEDS`] seeds).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "RangeFields")]
pub struct SeedRange {
    /// First seed.
    pub start: u64,
    /// One past the last seed.
    pub end: u64,
}

impl SeedRange {
    /// Number of seeds.
    pub fn len(&self) -> u64 {
        self.end - self.start
    }
    /// Never true for a parsed range (it holds at least one seed).
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }
}

impl core::fmt::Display for SeedRange {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}

impl core::str::FromStr for SeedRange {
    type Err = String;
    /// `A..B` (B excluded), `A..=B` (B included) or a single seed `A`.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("expected a seed range like 0..200, 0..=199 or 7, got {s:?}");
        let num = |t: &str| t.trim().parse::<u64>().map_err(|_| bad());
        let (start, end) = if let Some((a, b)) = s.split_once("..=") {
            (num(a)?, num(b)?.checked_add(1).ok_or_else(bad)?)
        } else if let Some((a, b)) = s.split_once("..") {
            (num(a)?, num(b)?)
        } else {
            let a = num(s)?;
            (a, a.checked_add(1).ok_or_else(bad)?)
        };
        if end <= start {
            return Err(format!(
                "empty seed range {s:?} (the end must be above the start)"
            ));
        }
        if end - start > MAX_SEEDS {
            return Err(format!(
                "seed range {s:?} holds {} seeds, more than {MAX_SEEDS} (split the study \
                 into ranges or shards)",
                end - start
            ));
        }
        Ok(SeedRange { start, end })
    }
}

/// The fields of a [`SeedRange`] as a file holds them, before the checks.
#[derive(Deserialize)]
struct RangeFields {
    start: u64,
    end: u64,
}

impl TryFrom<RangeFields> for SeedRange {
    type Error = String;
    fn try_from(f: RangeFields) -> Result<Self, String> {
        format!("{}..{}", f.start, f.end).parse()
    }
}

/// The fields of a [`Shard`] as a file holds them, before the checks.
#[derive(Deserialize)]
struct ShardFields {
    index: u32,
    count: u32,
}

impl TryFrom<ShardFields> for Shard {
    type Error = String;
    fn try_from(f: ShardFields) -> Result<Self, String> {
        format!("{}/{}", f.index, f.count).parse()
    }
}

/// Shard `index` of `count` (1-based: `1/4` .. `4/4`). Read from a file, it
/// is checked as when parsed from `--shard` (`1 <= index <= count`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "ShardFields")]
pub struct Shard {
    /// Which shard, `1..=count`.
    pub index: u32,
    /// How many shards the study is split into.
    pub count: u32,
}

impl Shard {
    /// The whole study in one shard.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// The seeds of `range` in this shard, ascending.
    pub fn seeds(&self, range: SeedRange) -> Vec<u64> {
        (range.start..range.end)
            .filter(|s| self.holds(s - range.start))
            .collect()
    }

    /// How many of the `len` items of a study (0-based `0..len`) belong to
    /// this shard ([`Shard::holds`]).
    pub fn items(&self, len: u64) -> u64 {
        let first = u64::from(self.index - 1);
        if len > first {
            (len - first).div_ceil(u64::from(self.count))
        } else {
            0
        }
    }

    /// Whether item `k` (0-based) of a study belongs to this shard: `k mod
    /// count == index - 1` (interleaved).
    pub fn holds(&self, k: u64) -> bool {
        k % u64::from(self.count) == u64::from(self.index - 1)
    }
}

impl core::fmt::Display for Shard {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl core::str::FromStr for Shard {
    type Err = String;
    /// `I/N` with `1 <= I <= N`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("expected a shard like 1/4 (I/N, 1 <= I <= N), got {s:?}"))?;
        let (i, n) = (
            i.trim()
                .parse::<u32>()
                .map_err(|_| format!("bad shard index in {s:?}"))?,
            n.trim()
                .parse::<u32>()
                .map_err(|_| format!("bad shard count in {s:?}"))?,
        );
        if n == 0 || i == 0 || i > n {
            return Err(format!(
                "shard {s:?} out of range: need 1 <= I <= N (shards are numbered 1..N)"
            ));
        }
        Ok(Shard { index: i, count: n })
    }
}
