//! The files of a robustness study: writing its directory, reading one back,
//! merging shards, and `runs.csv`.

use super::*;
use crate::studies::output::write_files;
use crate::studies::shards::{merged_shards, missing_shards};

/// Writes `runs.csv`, `table.md` and `summary.json` into `out` (atomically).
pub(super) fn write_dir(out: &Path, rep: &RobustnessReport) -> Result<PathBuf> {
    let json = serde_json::to_string_pretty(&RobustnessMeta::of(rep))?;
    let files = [
        ("runs.csv", runs_csv(rep)),
        ("table.md", markdown(rep)),
        ("summary.json", json + "\n"),
    ];
    Ok(write_files(out, &files)?)
}

/// Whether `dir` holds a `summary.json` written by `robustness --out` (so
/// `merge` knows which kind of study it merges).
pub fn is_robustness_dir(dir: &Path) -> bool {
    #[derive(Deserialize)]
    struct Kind {
        kind: String,
    }
    read(&dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<Kind>(&t).ok())
        .is_some_and(|k| k.kind == KIND)
}

/// Reads a directory written by `robustness --out` or by [`merge`]: its
/// summary and its runs (each checked against the run the study has at that
/// place), with their 0-based indices in the whole study.
pub fn read_dir(dir: &Path) -> Result<(RobustnessMeta, Vec<(usize, RobustRun)>)> {
    if !dir.is_dir() {
        return Err(RobustnessError::NoDirectory {
            dir: dir.to_path_buf(),
        });
    }
    let sj = dir.join("summary.json");
    let text = read(&sj)?;
    let meta: RobustnessMeta = match serde_json::from_str(&text) {
        Ok(m) => m,
        Err(error) => return Err(RobustnessError::Summary { path: sj, error }),
    };
    if meta.kind != KIND {
        return Err(RobustnessError::Kind {
            path: sj,
            kind: meta.kind,
        });
    }
    if meta.shard_count == 0
        || meta.shard.count
            != if meta.merged_shards.is_empty() {
                meta.shard_count
            } else {
                1
            }
        || meta
            .merged_shards
            .iter()
            .any(|&i| i == 0 || i > meta.shard_count)
    {
        return Err(RobustnessError::ShardFields {
            path: sj,
            shard: meta.shard,
            shard_count: meta.shard_count,
            merged_shards: meta.merged_shards,
        });
    }
    let cases = meta.all_cases();
    let per_cell = cases.len();
    if meta.study_runs != meta.conditions.len() * meta.deltas.len() * per_cell {
        return Err(RobustnessError::StudyRuns {
            path: sj,
            study_runs: meta.study_runs,
        });
    }
    // Indices in the study of this directory's runs, in order.
    let indices: Vec<usize> = if meta.merged_shards.is_empty() {
        (0..meta.study_runs)
            .filter(|&k| meta.shard.holds(k as u64))
            .collect()
    } else {
        (0..meta.study_runs)
            .filter(|&k| {
                meta.merged_shards.iter().any(|&i| {
                    Shard {
                        index: i,
                        count: meta.shard_count,
                    }
                    .holds(k as u64)
                })
            })
            .collect()
    };
    let csv = dir.join("runs.csv");
    let text = read(&csv)?;
    let mut lines = text.lines();
    if lines.next() != Some(RUNS_HEADER) {
        return Err(RobustnessError::Header { path: csv });
    }
    let rows: Vec<&str> = lines.filter(|l| !l.trim().is_empty()).collect();
    if rows.len() != meta.runs || rows.len() != indices.len() {
        return Err(RobustnessError::RowCount {
            path: csv,
            rows: rows.len(),
            runs: meta.runs,
            shard: meta.shard,
        });
    }
    let mut out = Vec::with_capacity(rows.len());
    for (i, (line, &k)) in rows.iter().zip(&indices).enumerate() {
        let ci = k / (meta.deltas.len() * per_cell);
        let di = (k / per_cell) % meta.deltas.len();
        let (group, label) = &cases[k % per_cell];
        match parse_run(
            line,
            &meta.conditions[ci],
            ci,
            meta.deltas[di],
            group,
            label,
        ) {
            Ok(run) => out.push((k, run)),
            Err(error) => {
                return Err(RobustnessError::Row {
                    path: csv,
                    line: i + 2,
                    error,
                });
            }
        }
    }
    Ok((meta, out))
}

/// Reads a file of a study directory as text.
fn read(path: &Path) -> Result<String> {
    use crate::scenario::limits::{MAX_FILE_BYTES, MAX_TABLE_BYTES, read_regular_file};
    let max = if path.ends_with("runs.csv") {
        MAX_TABLE_BYTES
    } else {
        MAX_FILE_BYTES
    };
    let file = |error| RobustnessError::File {
        path: path.to_path_buf(),
        error,
    };
    let bytes = read_regular_file(path, max).map_err(file)?;
    String::from_utf8(bytes).map_err(|_| {
        file(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "not a text file (invalid UTF-8)",
        ))
    })
}

/// Parses a line of `runs.csv`, which must be the run of `condition`, `delta`
/// and case `label`; the error names the field.
fn parse_run(
    line: &str,
    cond: &Condition,
    condition: usize,
    delta: f64,
    group: &'static str,
    label: &str,
) -> Result<RobustRun, String> {
    let f: Vec<&str> = line.split(',').collect();
    if f.len() != 13 {
        return Err(format!("{} fields, expected 13", f.len()));
    }
    let expect = [
        cond.disturbance.clone(),
        cond.magnitude.replace(',', ";"),
        format!("{delta}"),
        group.to_string(),
        label.to_string(),
    ];
    if f[..5] != expect {
        return Err(format!(
            "run {:?} where the study has {:?} (not the same study, or rows out of order)",
            f[..5].join(","),
            expect.join(",")
        ));
    }
    let outcome = [
        Outcome::GoalReached,
        Outcome::TimeLimit,
        Outcome::Stuck,
        Outcome::Diverged,
    ]
    .into_iter()
    .find(|o| o.name() == f[5])
    .ok_or_else(|| format!("unknown outcome {:?}", f[5]))?;
    let flag = |s: &str, name: &str| match s {
        "0" => Ok(false),
        "1" => Ok(true),
        _ => Err(format!("{name}: expected 0 or 1, got {s:?}")),
    };
    let num = |s: &str, name: &str| {
        s.parse::<f64>()
            .map_err(|_| format!("{name}: not a number: {s:?}"))
    };
    let count = |s: &str, name: &str| {
        s.parse::<usize>()
            .map_err(|_| format!("{name}: not a count: {s:?}"))
    };
    let fell = flag(f[6], "fell")?;
    let fall_time = if f[7].is_empty() {
        None
    } else {
        Some(num(f[7], "fall_time")?)
    };
    if fell != fall_time.is_some() {
        return Err("fell and fall_time disagree".into());
    }
    Ok(RobustRun {
        condition,
        delta,
        group,
        label: label.to_string(),
        outcome,
        fall_time,
        success: flag(f[8], "success")?,
        collision: flag(f[9], "collision")?,
        min_clearance: num(f[10], "min_clearance")?,
        steps: count(f[11], "steps")?,
        non_optimal_cycles: count(f[12], "non_optimal_cycles")?,
    })
}

/// Merges shard directories of one robustness study into `out`: checks that
/// they come from the same study (cases, random seeds, conditions, margins,
/// overrides, shard count) and that no shard appears twice and, unless
/// `allow_partial`, that every shard is there; writes the three files of the
/// whole study (nothing on error).
pub fn merge(inputs: &[PathBuf], out: &Path, allow_partial: bool) -> Result<RobustnessReport> {
    let mut parts = Vec::new();
    for d in inputs {
        parts.push(read_dir(d)?);
    }
    let shards = merged_shards(
        "robustness",
        "cases, random seeds, conditions, deltas, overrides and shard count",
        inputs,
        &parts,
        |(m, _)| {
            (
                m.study_key(),
                m.shard.index,
                &m.merged_shards[..],
                m.shard_count,
            )
        },
    )?;
    let m0 = parts[0].0.clone();
    let wall = parts.iter().fold(0.0, |w, (m, _)| w + m.wall_time_s);
    let mut runs: Vec<(usize, RobustRun)> = parts.into_iter().flat_map(|(_, r)| r).collect();
    runs.sort_by_key(|(k, _)| *k);
    if !allow_partial && runs.len() < m0.study_runs {
        let missing = missing_shards(&shards, m0.shard_count);
        return Err(RobustnessError::Incomplete {
            runs: runs.len(),
            expected: m0.study_runs,
            missing: missing.join(", "),
        });
    }
    let rep = RobustnessReport {
        cases: m0.cases,
        random: m0.random,
        conditions: m0.conditions,
        deltas: m0.deltas,
        runs: runs.into_iter().map(|(_, r)| r).collect(),
        study_runs: m0.study_runs,
        wall_time_s: wall,
        jobs: 0,
        sets: m0.sets,
        shard: Shard::ALL,
        shard_count: m0.shard_count,
        merged_shards: shards,
    };
    write_dir(out, &rep)?;
    Ok(rep)
}

/// Header of `runs.csv`.
pub const RUNS_HEADER: &str = "disturbance,magnitude,delta,group,case,outcome,fell,fall_time,\
success,collision,min_clearance,steps,non_optimal_cycles";

/// Every run as CSV (with [`RUNS_HEADER`]).
pub fn runs_csv(rep: &RobustnessReport) -> String {
    let mut s = String::from(RUNS_HEADER);
    s.push('\n');
    for r in &rep.runs {
        let c = &rep.conditions[r.condition];
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            c.disturbance,
            c.magnitude.replace(',', ";"),
            r.delta,
            r.group,
            r.label,
            r.outcome.name(),
            u8::from(r.fall_time.is_some()),
            r.fall_time.map_or(String::new(), |t| format!("{t:.3}")),
            u8::from(r.success),
            u8::from(r.collision),
            r.min_clearance,
            r.steps,
            r.non_optimal_cycles
        );
    }
    s
}
