//! Output files: checked before any GPU work, written whole or not at all.
//!
//! `check` refuses a path whose format Speculum cannot write (a `.jpg` for a PNG) or
//! whose folder does not exist, so a long render never fails at its end; `write_atomic`
//! writes a temporary file beside the target and renames it over the target, so a
//! failure leaves no half-written or empty file behind. `-` means standard output for
//! the JSON reports.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// What an output holds, for the format check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// An image: must end in `.png`.
    Png,
    /// A JSON report: any name, or `-` for standard output.
    Json,
}

/// Checks that `path` can receive output of `kind`: the right extension and an existing
/// folder (the file itself is created or replaced later).
pub fn check(path: &Path, kind: Kind) -> Result<()> {
    let bad = |detail: String| Error::Output {
        path: path.into(),
        detail,
    };
    if kind == Kind::Json && path == Path::new("-") {
        return Ok(());
    }
    if kind == Kind::Png {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        if ext.as_deref() != Some("png") {
            return Err(bad("images are written as PNG: give a path ending in .png".into()));
        }
    }
    if path.file_name().is_none() {
        return Err(bad("not a file name".into()));
    }
    let dir = folder(path);
    if !dir.is_dir() {
        return Err(bad(format!("folder '{}' does not exist", dir.display())));
    }
    if path.is_dir() {
        return Err(bad("is a folder".into()));
    }
    Ok(())
}

/// Checks that folder `dir` can receive a sequence of files: it is a folder, or does
/// not exist yet in an existing folder, and a file can be created there (tried with a
/// temporary file, removed again).
pub fn check_dir(dir: &Path) -> Result<()> {
    let bad = |detail: String| Error::Output {
        path: dir.into(),
        detail,
    };
    let existing = if dir.exists() {
        if !dir.is_dir() {
            return Err(bad("is not a folder".into()));
        }
        dir.to_path_buf()
    } else {
        let parent = folder(dir);
        if !parent.is_dir() {
            return Err(bad(format!("folder '{}' does not exist", parent.display())));
        }
        parent
    };
    let probe = existing.join(format!(".speculum-probe.{}.tmp", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| bad(format!("cannot write there: {e}")))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

fn folder(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename:
/// readers see the old file or the whole new one, never a part. `-` writes to stdout.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let fail = |e: std::io::Error| Error::Output {
        path: path.into(),
        detail: e.to_string(),
    };
    if path == Path::new("-") {
        let mut out = std::io::stdout().lock();
        return out.write_all(bytes).and_then(|_| out.flush()).map_err(fail);
    }
    let tmp = temporary(path);
    let result = std::fs::write(&tmp, bytes).and_then(|_| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(fail)
}

/// Outputs written together: every file goes to a temporary beside its target first,
/// and only when all of them are written are they renamed into place, so a failure
/// leaves none of the targets changed (`-`, stdout, is written last).
#[derive(Default)]
pub struct Batch {
    files: Vec<(PathBuf, Vec<u8>)>,
}

impl Batch {
    pub fn add(&mut self, path: &Path, bytes: Vec<u8>) {
        self.files.push((path.to_path_buf(), bytes));
    }

    /// Writes every output, or none of the files.
    pub fn commit(self) -> Result<()> {
        let (stdout, files): (Vec<_>, Vec<_>) = self.files.into_iter().partition(|(p, _)| p == Path::new("-"));
        let mut written: Vec<(PathBuf, PathBuf)> = Vec::new();
        for (path, bytes) in &files {
            let tmp = temporary(path);
            if let Err(e) = std::fs::write(&tmp, bytes) {
                let _ = std::fs::remove_file(&tmp);
                for (t, _) in &written {
                    let _ = std::fs::remove_file(t);
                }
                return Err(Error::Output {
                    path: path.clone(),
                    detail: e.to_string(),
                });
            }
            written.push((tmp, path.clone()));
        }
        for (tmp, path) in written {
            std::fs::rename(&tmp, &path).map_err(|e| Error::Output {
                path: path.clone(),
                detail: e.to_string(),
            })?;
        }
        for (path, bytes) in stdout {
            write_atomic(&path, &bytes)?;
        }
        Ok(())
    }
}

fn temporary(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    folder(path).join(format!(".{name}.{}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_refuses_wrong_formats_and_missing_folders() {
        let dir = tempfile::tempdir().unwrap();
        assert!(check(&dir.path().join("a.png"), Kind::Png).is_ok());
        assert!(check(&dir.path().join("a.PNG"), Kind::Png).is_ok());
        assert!(check(&dir.path().join("a.jpg"), Kind::Png).is_err());
        assert!(check(&dir.path().join("no/such/a.png"), Kind::Png).is_err());
        assert!(check(&dir.path().join("t.json"), Kind::Json).is_ok());
        assert!(check(Path::new("-"), Kind::Json).is_ok());
        assert!(check(Path::new("-"), Kind::Png).is_err());
        assert!(check(dir.path(), Kind::Json).is_err(), "a folder is not a file");
    }

    #[test]
    fn atomic_write_replaces_whole_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.json");
        write_atomic(&p, b"old").unwrap();
        write_atomic(&p, b"new contents").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new contents");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
        assert!(write_atomic(&dir.path().join("missing/r.json"), b"x").is_err());
    }

    #[test]
    fn batch_writes_all_or_none() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.json"));
        let mut batch = Batch::default();
        batch.add(&a, b"image".to_vec());
        batch.add(&dir.path().join("missing/b.json"), b"report".to_vec());
        assert!(batch.commit().is_err());
        assert!(!a.exists(), "a failed batch leaves no file");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "and no temporary");
        let mut batch = Batch::default();
        batch.add(&a, b"image".to_vec());
        batch.add(&b, b"report".to_vec());
        batch.commit().unwrap();
        assert_eq!(
            (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap()),
            (b"image".to_vec(), b"report".to_vec())
        );
    }
}
