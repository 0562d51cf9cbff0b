//! The CSV logs of a run (`cycles.csv`, `footsteps.csv`, `trajectory.csv`) and
//! `summary.json`, and the output directory written atomically.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::Summary;
use crate::sim::SimResult;

fn write_file(path: &Path, text: &str) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    f.write_all(text.as_bytes())?;
    f.flush()
}

/// Writes `cycles.csv`, `footsteps.csv`, `trajectory.csv` (every
/// `trajectory_every`-th sample) and `summary.json` into `dir`.
pub fn write_logs(
    r: &SimResult,
    summary: &Summary,
    dir: &Path,
    trajectory_every: usize,
) -> std::io::Result<()> {
    let mut s = String::from(
        "t,time_in_step,step,stance,x0_px,x0_py,x0_vx,x0_vy,x0_theta,active_obstacles,truncated,\
status,source,iterations,active_set,compute_ns,max_violation,cost,min_h0,relax_gait,relax_safety,relax_capture,foot_x,foot_y,omega,landed\n",
    );
    for c in &r.cycles {
        let o = &c.output;
        let x0 = &o.plan.x0;
        let _ = writeln!(
            s,
            "{:.3},{:.3},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:e},{},{},{},{},{},{},{},{},{}",
            c.time,
            c.time_in_step,
            c.step,
            c.stance_side.name(),
            x0.position.x,
            x0.position.y,
            x0.velocity.x,
            x0.velocity.y,
            x0.heading,
            o.info.active_obstacles,
            u8::from(o.info.obstacles_truncated),
            o.status.name(),
            o.info.source.name(),
            o.info.iterations,
            o.info.active_set_size,
            c.compute_ns,
            o.info.max_violation,
            o.info.cost,
            o.info.min_h0,
            o.info.relax_gait,
            o.info.relax_safety,
            o.info.relax_capture,
            o.foot_target.x,
            o.foot_target.y,
            o.turning_rate,
            u8::from(c.landed),
        );
    }
    write_file(&dir.join("cycles.csv"), &s)?;

    let mut s = String::from("step,side,x,y,t,heading,clearance\n");
    for f in &r.footsteps {
        let _ = writeln!(
            s,
            "{},{},{},{},{:.3},{},{}",
            f.index,
            f.side.name(),
            f.position.x,
            f.position.y,
            f.time,
            f.heading,
            f.clearance
        );
    }
    write_file(&dir.join("footsteps.csv"), &s)?;

    let mut s = String::from("t,px,py,vx,vy,theta,omega,stance,clearance\n");
    let every = trajectory_every.max(1);
    for (i, p) in r.samples.iter().enumerate() {
        if i % every != 0 && i + 1 != r.samples.len() {
            continue;
        }
        let _ = writeln!(
            s,
            "{:.3},{},{},{},{},{},{},{},{}",
            p.time,
            p.position.x,
            p.position.y,
            p.velocity.x,
            p.velocity.y,
            p.heading,
            p.turning_rate,
            p.stance_side.name(),
            p.clearance
        );
    }
    write_file(&dir.join("trajectory.csv"), &s)?;

    let json = serde_json::to_string_pretty(summary).map_err(std::io::Error::other)?;
    write_file(&dir.join("summary.json"), &(json + "\n"))
}

/// An output directory written atomically: files go into a hidden temporary
/// sibling (`.<name>.tmp-<pid>`), which [`OutputDir::commit`] renames onto the
/// final path. An existing final path is replaced only if it is empty or holds a
/// previous output (a `summary.json`, or only `cycle_NNNNN.npz` files of a
/// previous `run --export-qps`); any other existing path is refused by
/// [`OutputDir::create`], before anything is written. Dropped without `commit`,
/// the temporary directory is removed, and so are the parent directories that
/// `create` made, so a failed command leaves nothing behind. A final path that
/// is a symbolic link to a directory is written through (the link stays and
/// names the new directory); a dangling link is refused.
///
/// Errors of `create` and [`OutputDir::preflight`] do not repeat the path; the
/// caller names it (e.g. `--out DIR: ...`).
#[derive(Debug)]
pub struct OutputDir {
    /// The path as given (returned by `commit`).
    given: PathBuf,
    /// Where the directory goes: `given`, or the directory a link there names.
    final_path: PathBuf,
    tmp: PathBuf,
    /// Parent directories made by `create`, innermost first.
    made: Vec<PathBuf>,
    committed: bool,
}

impl OutputDir {
    /// Checks, without creating anything, that [`OutputDir::create`] can make
    /// `final_path`: it has a usable last component, it is not an existing file
    /// or a directory that is not a previous output, and its nearest existing
    /// ancestor is a directory. Commands that run for long call this first.
    pub fn preflight(final_path: &Path) -> std::io::Result<()> {
        let (_, parent, _, missing) = Self::plan(final_path)?;
        // The nearest existing ancestor must take a new directory.
        let base = missing
            .last()
            .and_then(|p| p.parent())
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(if missing.is_empty() {
                parent.as_path()
            } else {
                Path::new(".")
            });
        let probe = base.join(format!(".ldcbf-probe-{}", std::process::id()));
        std::fs::create_dir(&probe).map_err(|e| {
            std::io::Error::other(format!(
                "cannot create a directory in {}: {e}",
                base.display()
            ))
        })?;
        let _ = std::fs::remove_dir(&probe);
        Ok(())
    }

    /// The checks of [`OutputDir::preflight`]; returns the final path (a
    /// symbolic link resolved to its directory, so that the output is written
    /// through the link and the link stays), its parent, its name and the
    /// parent directories that do not exist yet (innermost first).
    fn plan(
        final_path: &Path,
    ) -> std::io::Result<(PathBuf, PathBuf, std::ffi::OsString, Vec<PathBuf>)> {
        let err = |m: String| Err(std::io::Error::other(m));
        let raw = final_path.as_os_str().as_encoded_bytes();
        if raw.is_empty()
            || raw == b"."
            || raw == b".."
            || raw.ends_with(b"/.")
            || raw.ends_with(b"/..")
        {
            return err(
                "has no usable last component (it ends in `.` or `..`; give a directory name)"
                    .into(),
            );
        }
        let resolved;
        let final_path = match std::fs::symlink_metadata(final_path) {
            Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(final_path) {
                Ok(t) => {
                    resolved = t;
                    resolved.as_path()
                }
                Err(e) => {
                    let to = std::fs::read_link(final_path)
                        .map_or_else(|_| "?".into(), |t| t.display().to_string());
                    return err(format!(
                        "is a symbolic link to {to}, which cannot be followed ({e})"
                    ));
                }
            },
            _ => final_path,
        };
        let Some(name) = final_path
            .file_name()
            .filter(|s| !s.is_empty() && *s != "." && *s != "..")
        else {
            return err("has no usable last component (give a directory name)".into());
        };
        let parent = final_path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        match std::fs::metadata(final_path) {
            Ok(m) if !m.is_dir() => return err("exists and is a file, not a directory".into()),
            Ok(_) if !replaceable(final_path) => {
                return err(
                    "exists and is not a previous ldcbf-sim output (no summary.json); \
                     refusing to replace it"
                        .into(),
                );
            }
            _ => {}
        }
        let mut missing = Vec::new();
        let mut p = parent.as_path();
        loop {
            match std::fs::metadata(p) {
                Ok(m) if m.is_dir() => break,
                Ok(_) => return err(format!("{} is a file, not a directory", p.display())),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                    missing.push(p.to_path_buf());
                    match p.parent().filter(|q| !q.as_os_str().is_empty()) {
                        Some(q) => p = q,
                        None => break,
                    }
                }
                Err(e) => return err(format!("{}: {e}", p.display())),
            }
        }
        Ok((
            final_path.to_path_buf(),
            parent,
            name.to_os_string(),
            missing,
        ))
    }

    /// Creates the temporary directory for `final_path` (and its parents).
    pub fn create(final_path: &Path) -> std::io::Result<Self> {
        let (resolved, parent, name, missing) = Self::plan(final_path)?;
        let mut dir = OutputDir {
            given: final_path.to_path_buf(),
            final_path: resolved,
            tmp: parent.join(tmp_name(&name)),
            made: Vec::new(),
            committed: false,
        };
        // Outermost first, remembered so that `drop` can remove them again.
        for p in missing.iter().rev() {
            std::fs::create_dir(p).map_err(|e| {
                std::io::Error::other(format!("cannot create {}: {e}", p.display()))
            })?;
            dir.made.insert(0, p.clone());
        }
        if dir.tmp.exists() {
            std::fs::remove_dir_all(&dir.tmp)?;
        }
        std::fs::create_dir(&dir.tmp).map_err(|e| {
            std::io::Error::other(format!(
                "cannot create the temporary directory {}: {e}",
                dir.tmp.display()
            ))
        })?;
        Ok(dir)
    }

    /// Where to write the files now.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// Moves the finished directory into place and returns its final path.
    pub fn commit(mut self) -> std::io::Result<PathBuf> {
        let mut old = None;
        if self.final_path.exists() {
            if !replaceable(&self.final_path) {
                return Err(std::io::Error::other(
                    "appeared meanwhile and is not a previous ldcbf-sim output; refusing to replace it",
                ));
            }
            let trash = self.tmp.with_extension("old");
            std::fs::rename(&self.final_path, &trash)?;
            old = Some(trash);
        }
        std::fs::rename(&self.tmp, &self.final_path)?;
        self.committed = true;
        if let Some(trash) = old {
            std::fs::remove_dir_all(trash)?;
        }
        Ok(self.given.clone())
    }
}

/// Longest part of the final name kept in the temporary sibling's name, bytes:
/// with the dot, `.tmp-`, a counter and a process id the name stays under the
/// 255 bytes a file name may have.
const TMP_NAME_KEEP: usize = 200;

/// The temporary sibling of a directory named `name`: `.<name>.tmp-<pid>`, or,
/// for a name over [`TMP_NAME_KEEP`] bytes, its first bytes (whole
/// characters) and a counter of this process, `.<start>~<n>.tmp-<pid>`, so
/// that a name of up to 255 bytes (any bytes: it need not be UTF-8) gets a
/// sibling the file system takes, and two long names that begin alike get
/// two siblings.
fn tmp_name(name: &std::ffi::OsStr) -> std::ffi::OsString {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static LONG: AtomicUsize = AtomicUsize::new(0);
    let pid = std::process::id();
    let bytes = name.as_encoded_bytes();
    let mut out = std::ffi::OsString::from(".");
    if bytes.len() <= TMP_NAME_KEEP {
        out.push(name);
    } else {
        let lossy = name.to_string_lossy();
        let mut cut = TMP_NAME_KEEP.min(lossy.len());
        while !lossy.is_char_boundary(cut) {
            cut -= 1;
        }
        out.push(&lossy[..cut]);
        out.push(format!("~{}", LONG.fetch_add(1, Ordering::Relaxed)));
    }
    out.push(format!(".tmp-{pid}"));
    out
}

/// An existing output path may be replaced: an empty directory, a previous run
/// or batch (a `summary.json`) or a previous QP export (only `cycle_NNNNN.npz`).
fn replaceable(p: &Path) -> bool {
    let is_qp = |n: &std::ffi::OsStr| {
        n.to_str().is_some_and(|n| {
            n.strip_prefix("cycle_")
                .and_then(|r| r.strip_suffix(".npz"))
                .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
        })
    };
    p.is_dir()
        && (p.join("summary.json").is_file()
            || std::fs::read_dir(p).is_ok_and(|d| {
                d.into_iter()
                    .all(|e| e.is_ok_and(|e| is_qp(&e.file_name()) && e.path().is_file()))
            }))
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.tmp);
            // Only empty directories go (`remove_dir` refuses others).
            for p in &self.made {
                let _ = std::fs::remove_dir(p);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::ffi::OsStrExt;

    #[test]
    fn temporary_names_fit_a_file_name_and_keep_any_bytes() {
        let pid = std::process::id();
        let short = tmp_name(std::ffi::OsStr::new("out"));
        assert_eq!(short, std::ffi::OsString::from(format!(".out.tmp-{pid}")));
        let raw = std::ffi::OsStr::from_bytes(b"o-\xff");
        assert_eq!(tmp_name(raw).as_bytes()[..4], *b".o-\xff");
        let long = "é".repeat(127); // 254 bytes
        let (a, b) = (
            tmp_name(std::ffi::OsStr::new(&long)),
            tmp_name(std::ffi::OsStr::new(&long)),
        );
        assert_ne!(a, b, "two long names that begin alike get two siblings");
        for t in [a, b] {
            assert!(t.len() <= 255, "{} bytes", t.len());
            assert!(
                t.to_str()
                    .is_some_and(|t| t.starts_with(&format!(".{}~", "é".repeat(100))))
            );
        }
    }
}
