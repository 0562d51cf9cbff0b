//! Writing a study's directory, all its files or none
//! ([`crate::report::OutputDir`]): the one writer of `batch`, `robustness` and
//! their `merge`.

use std::path::{Path, PathBuf};

use crate::report::OutputDir;

/// Why a study's directory was not written (nothing of it is left behind).
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The output directory cannot be created.
    #[error("--out {}", path.display())]
    Out {
        /// The `--out` path.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("{}: {error}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The finished directory could not be moved into place.
    #[error("cannot move the results into {}", path.display())]
    Commit {
        /// The `--out` path.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// Writes `files` (name, contents) into the directory `out`, atomically:
/// they appear together once all are written, or not at all. Returns the
/// directory's final path.
pub fn write_files(out: &Path, files: &[(&str, String)]) -> Result<PathBuf, WriteError> {
    let dir = OutputDir::create(out).map_err(|source| WriteError::Out {
        path: out.to_path_buf(),
        source,
    })?;
    for (name, text) in files {
        let path = dir.path().join(name);
        std::fs::write(&path, text).map_err(|error| WriteError::File { path, error })?;
    }
    dir.commit().map_err(|source| WriteError::Commit {
        path: out.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_files_appear_together_or_not_at_all() {
        let base = std::env::temp_dir().join(format!("ldcbf-write-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        let out = base.join("study");
        let files = [("a.csv", "1\n".to_string()), ("b.json", "{}\n".to_string())];
        let dir = write_files(&out, &files).unwrap();
        assert_eq!(std::fs::read_to_string(dir.join("a.csv")).unwrap(), "1\n");
        assert_eq!(std::fs::read_to_string(dir.join("b.json")).unwrap(), "{}\n");
        // A file name that cannot be written: the error names it, and no
        // directory appears.
        let bad = base.join("bad");
        let err = write_files(
            &bad,
            &[("ok.csv", String::new()), ("no/such.csv", String::new())],
        )
        .unwrap_err();
        assert!(matches!(err, WriteError::File { .. }), "{err}");
        assert!(err.to_string().contains("such.csv"), "{err}");
        assert!(!bad.exists());
        std::fs::remove_dir_all(&base).unwrap();
    }
}
