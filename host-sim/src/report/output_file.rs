//! One output file written atomically, with the rules of the output
//! directories ([`super::OutputDir`]) for a single file: the text goes into a
//! hidden temporary sibling (`.<name>.tmp-<pid>`) renamed onto the final
//! path, so a failed command leaves nothing behind; an existing final path
//! is replaced only if it is a regular file that `previous` recognises as
//! an earlier output of the same command (or empty); a directory, a device,
//! a FIFO, a socket or any other file is refused before anything is
//! written. A final path that is a symbolic link to a file is written
//! through (the link stays); a dangling link is refused. The parent
//! directory must exist.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Checks, before anything is computed or written, that
/// [`write_output_file`] may write `path`; returns the path to write (a
/// symbolic link resolved). The error does not repeat the path.
pub fn check_output_file(
    path: &Path,
    previous: impl Fn(&Path) -> bool,
) -> std::io::Result<PathBuf> {
    let err = |m: String| Err(std::io::Error::other(m));
    let target: PathBuf = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(path) {
            Ok(t) => t,
            Err(e) => return err(format!("is a symbolic link that cannot be followed ({e})")),
        },
        _ => path.to_path_buf(),
    };
    if target
        .file_name()
        .and_then(|s| s.to_str())
        .is_none_or(|s| s.is_empty() || s == "." || s == "..")
    {
        return err("has no usable last component (give a file name)".into());
    }
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => return err("is a directory, not a file".into()),
        Ok(m) if !m.is_file() => {
            return err(
                "is not a regular file (a device, a FIFO or a socket); refusing to write it".into(),
            );
        }
        Ok(m) if m.len() > 0 && !previous(&target) => {
            return err(
                "exists and is not a previous output of this command; refusing to replace it"
                    .into(),
            );
        }
        _ => {}
    }
    let parent = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !parent.is_dir() {
        return err(format!("{} is not a directory", parent.display()));
    }
    Ok(target)
}

/// Writes `text` to `path` (module docs) after [`check_output_file`];
/// `previous` says whether an existing regular file there is an earlier
/// output that may be replaced. The error does not repeat the path (the
/// caller names it).
pub fn write_output_file(
    path: &Path,
    text: &str,
    previous: impl Fn(&Path) -> bool,
) -> std::io::Result<()> {
    let target = check_output_file(path, previous)?;
    let name = target.file_name().and_then(|s| s.to_str()).unwrap_or("out");
    let parent = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let tmp = Temp(parent.join(format!(".{name}.tmp-{}", std::process::id())));
    // A stale temporary of this pid goes; a new one is made (never a FIFO
    // or a link someone left there).
    let _ = std::fs::remove_file(&tmp.0);
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp.0)?;
    f.write_all(text.as_bytes())?;
    f.sync_all()?;
    drop(f);
    std::fs::rename(&tmp.0, &target)?;
    std::mem::forget(tmp);
    Ok(())
}

/// A temporary file removed when dropped (on every error path).
struct Temp(PathBuf);

impl Drop for Temp {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_atomically_and_refuses_what_it_may_not_replace() {
        let base = std::env::temp_dir().join(format!("ldcbf-output-file-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        std::fs::create_dir_all(base.join("dir")).unwrap();
        let is_ours = |p: &Path| std::fs::read_to_string(p).is_ok_and(|t| t.starts_with("ours"));
        let out = base.join("a.json");
        write_output_file(&out, "ours 1", is_ours).unwrap();
        write_output_file(&out, "ours 2", is_ours).unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "ours 2");
        // Someone else's file, a directory, a device: refused, untouched,
        // no temporary left.
        let other = base.join("notes.txt");
        std::fs::write(&other, "keep").unwrap();
        for (p, what) in [
            (other.as_path(), "previous output"),
            (&base.join("dir"), "directory"),
            (Path::new("/dev/null"), "regular file"),
        ] {
            let e = write_output_file(p, "ours 3", is_ours).unwrap_err();
            assert!(e.to_string().contains(what), "{e}");
        }
        assert_eq!(std::fs::read_to_string(&other).unwrap(), "keep");
        let mut names: Vec<String> = std::fs::read_dir(&base)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["a.json", "dir", "notes.txt"]);
        assert_eq!(std::fs::read_dir(base.join("dir")).unwrap().count(), 0);
        std::fs::remove_dir_all(&base).unwrap();
    }
}
