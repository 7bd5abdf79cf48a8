//! Output files: checked before any GPU work, written whole or not at all.
//!
//! `check` refuses a path whose format Speculum cannot write (a `.jpg` for a PNG), whose
//! folder does not exist or cannot be written, or that names something other than a
//! regular file (a folder, a device such as `/dev/full`, a FIFO, a socket), so a long
//! render never fails at its end and never replaces what is not a file. A symlink is
//! written through: its target (which must exist and be a regular file) gets the new
//! contents and the link stays. `check_distinct` refuses two outputs of one run that
//! name the same file, and an output that names one of the run's inputs.
//! `write_atomic` writes a temporary file beside the target and renames it over the
//! target, so a failure leaves no half-written or empty file behind. `-` means standard
//! output for the JSON reports.

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
    let target = write_target(path)?;
    let dir = folder(&target);
    if !dir.is_dir() {
        return Err(bad(format!("folder '{}' does not exist", dir.display())));
    }
    probe_writable(&dir).map_err(|e| bad(format!("cannot write in folder '{}': {e}", dir.display())))
}

/// The file a write to `path` replaces: `path` itself, or, for a symlink, the file it
/// leads to (which must exist). Refuses anything that exists and is not a regular
/// file: outputs never replace a folder, a device, a FIFO or a socket.
pub fn write_target(path: &Path) -> Result<PathBuf> {
    let bad = |detail: String| Error::Output {
        path: path.into(),
        detail,
    };
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => std::fs::canonicalize(path)
            .map_err(|e| bad(format!("a symlink whose target cannot be written through ({e})")))?,
        _ => path.to_path_buf(),
    };
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => Err(bad("is a folder".into())),
        Ok(m) if !m.is_file() => Err(bad(format!(
            "is not a regular file ({}): outputs only create or replace regular files",
            crate::error::file_kind(&m)
        ))),
        _ => Ok(target),
    }
}

/// Creates and removes a temporary file in `dir`: the folder is writable now (read-only
/// mounts, permissions and immutable folders all answer here, before any GPU work).
fn probe_writable(dir: &Path) -> std::io::Result<()> {
    let probe = dir.join(format!(".speculum-probe.{}.tmp", std::process::id()));
    std::fs::OpenOptions::new().write(true).create_new(true).open(&probe)?;
    std::fs::remove_file(&probe)
}

/// The identity of an output or input path for collision checks: `-` for standard
/// output, else the absolute path of the file it reads or replaces (symlinks resolved,
/// `./` and `..` gone), whether or not it exists yet.
fn identity(path: &Path) -> PathBuf {
    if path == Path::new("-") {
        return path.to_path_buf();
    }
    if let Ok(p) = std::fs::canonicalize(path) {
        return p;
    }
    let dir = std::fs::canonicalize(folder(path)).unwrap_or_else(|_| folder(path));
    match path.file_name() {
        Some(name) => dir.join(name),
        None => path.to_path_buf(),
    }
}

/// Refuses two `outputs` (flag, path) of one run that name the same file (standard
/// output counts once too), and an output that names one of the run's `inputs`.
pub fn check_distinct(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<()> {
    for (i, (flag, path)) in outputs.iter().enumerate() {
        let id = identity(path);
        if let Some((other, _)) = outputs[..i].iter().find(|(_, p)| identity(p) == id) {
            return Err(Error::Output {
                path: path.to_path_buf(),
                detail: format!("{other} and {flag} name the same file: give each output its own"),
            });
        }
        if let Some((input, _)) = inputs.iter().find(|(_, p)| *p != Path::new("-") && identity(p) == id) {
            return Err(Error::Output {
                path: path.to_path_buf(),
                detail: format!("{flag} would overwrite the input {input}"),
            });
        }
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
    probe_writable(&existing).map_err(|e| bad(format!("cannot write there: {e}")))
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
    // Checked again at write time: what the path names may have changed since `check`.
    let target = write_target(path)?;
    let tmp = temporary(&target);
    let result = std::fs::write(&tmp, bytes).and_then(|_| std::fs::rename(&tmp, &target));
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
        let cleanup = |written: &[(PathBuf, PathBuf)]| {
            for (t, _) in written {
                let _ = std::fs::remove_file(t);
            }
        };
        for (path, bytes) in &files {
            let target = match write_target(path) {
                Ok(t) => t,
                Err(e) => {
                    cleanup(&written);
                    return Err(e);
                }
            };
            let tmp = temporary(&target);
            if let Err(e) = std::fs::write(&tmp, bytes) {
                let _ = std::fs::remove_file(&tmp);
                cleanup(&written);
                return Err(Error::Output {
                    path: path.clone(),
                    detail: e.to_string(),
                });
            }
            written.push((tmp, target));
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

/// Tightly packed RGBA8 encoded as a PNG.
pub fn png_bytes(rgba: &[u8], width: u32, height: u32) -> Result<Vec<u8>> {
    let mut png = Vec::new();
    image::write_buffer_with_format(
        &mut std::io::Cursor::new(&mut png),
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
        image::ImageFormat::Png,
    )
    .map_err(|e| Error::Input(format!("PNG encoding failed: {e}")))?;
    Ok(png)
}

/// Writes tightly packed RGBA8 as a PNG, atomically (see `output::write_atomic`).
pub fn save_png(path: &Path, rgba: &[u8], width: u32, height: u32) -> Result<()> {
    write_atomic(path, &png_bytes(rgba, width, height)?)
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
    fn what_is_not_a_regular_file_is_never_replaced() {
        let dir = tempfile::tempdir().unwrap();
        for dev in ["/dev/null", "/dev/full"] {
            let e = check(Path::new(dev), Kind::Json).unwrap_err().to_string();
            assert!(e.contains("not a regular file (a device)"), "{e}");
            assert!(write_atomic(Path::new(dev), b"x").is_err());
            assert!(!std::fs::metadata(dev).unwrap().is_file(), "{dev} is still a device");
        }
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if made {
            let e = check(&fifo, Kind::Json).unwrap_err().to_string();
            assert!(e.contains("a FIFO"), "{e}");
            assert!(write_atomic(&fifo, b"x").is_err());
            use std::os::unix::fs::FileTypeExt;
            assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
        } else {
            eprintln!("SKIPPED: no mkfifo here, the FIFO case did not run");
        }
        let e = check(dir.path(), Kind::Json).unwrap_err().to_string();
        assert!(e.contains("is a folder"), "{e}");
    }

    #[test]
    fn a_symlink_is_written_through_and_stays_a_link() {
        let dir = tempfile::tempdir().unwrap();
        let (target, link) = (dir.path().join("real.json"), dir.path().join("link.json"));
        std::fs::write(&target, b"old").unwrap();
        std::os::unix::fs::symlink(&target, &link).unwrap();
        check(&link, Kind::Json).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        // Through a batch too.
        let mut batch = Batch::default();
        batch.add(&link, b"batch".to_vec());
        batch.commit().unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"batch");
        // A link to a device is refused like the device; a dangling link is refused.
        let to_dev = dir.path().join("dev.json");
        std::os::unix::fs::symlink("/dev/full", &to_dev).unwrap();
        assert!(check(&to_dev, Kind::Json).unwrap_err().to_string().contains("a device"));
        let dangling = dir.path().join("dangling.json");
        std::os::unix::fs::symlink(dir.path().join("nowhere/x.json"), &dangling).unwrap();
        assert!(check(&dangling, Kind::Json)
            .unwrap_err()
            .to_string()
            .contains("symlink"));
    }

    #[test]
    fn outputs_that_name_the_same_file_or_an_input_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let a = d.join("a.png");
        let dot = d.join(".").join("a.png");
        let e = check_distinct(&[("--out", &a), ("--fail-mask", &dot)], &[]).unwrap_err();
        assert!(
            e.to_string().contains("--out and --fail-mask name the same file"),
            "{e}"
        );
        let stdout = Path::new("-");
        assert!(check_distinct(&[("--json", stdout), ("--markdown", stdout)], &[]).is_err());
        std::fs::write(&a, b"input").unwrap();
        let link = d.join("l.png");
        std::os::unix::fs::symlink(&a, &link).unwrap();
        let e = check_distinct(&[("--json", &link)], &[("image A", &a)]).unwrap_err();
        assert!(
            e.to_string().contains("--json would overwrite the input image A"),
            "{e}"
        );
        check_distinct(
            &[("--out", &a), ("--timings", &d.join("t.json")), ("--json", stdout)],
            &[],
        )
        .unwrap();
    }

    #[test]
    fn an_unwritable_folder_is_found_by_check() {
        let dir = tempfile::tempdir().unwrap();
        let ro = dir.path().join("ro");
        std::fs::create_dir(&ro).unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        if probe_writable(&ro).is_ok() {
            // Root writes through permissions: try an immutable folder instead.
            let immutable = std::process::Command::new("chattr")
                .arg("+i")
                .arg(&ro)
                .status()
                .is_ok_and(|s| s.success());
            if !immutable {
                eprintln!("SKIPPED: as root, with no chattr +i here, no folder is unwritable");
                return;
            }
        }
        let e = check(&ro.join("a.png"), Kind::Png).unwrap_err().to_string();
        assert!(e.contains("cannot write in folder"), "{e}");
        let _ = std::process::Command::new("chattr").arg("-i").arg(&ro).status();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
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
