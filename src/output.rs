//! Atomic output: everything rtow writes goes to a temporary file in the target
//! folder first and is renamed into place, so a failed or interrupted run never
//! leaves a half-written file behind.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::Path;

fn output_error(path: &Path, message: impl std::fmt::Display) -> Error {
    // tempfile appends ` at path "<dir>/.rtow-XXXX.tmp"`; the temporary name
    // means nothing to the user, the target path is already in the message.
    let message = message.to_string();
    let message = message.split(" at path ").next().unwrap_or_default().to_string();
    Error::Output { path: path.to_path_buf(), message }
}

/// The folder `path` will be written in, checked to exist.
fn target_dir(path: &Path) -> Result<&Path> {
    if path.is_dir() {
        return Err(output_error(path, "is a directory"));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.exists() {
        return Err(output_error(path, format!("folder {} does not exist", dir.display())));
    }
    if !dir.is_dir() {
        return Err(output_error(path, format!("{} is not a folder", dir.display())));
    }
    Ok(dir)
}

fn temp_in(dir: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    let mut b = tempfile::Builder::new();
    b.prefix(".rtow-").suffix(".tmp");
    // tempfile creates files readable by the owner only (0600); outputs are
    // ordinary files, so ask for 0666 and let the umask decide, as `File::create` does.
    #[cfg(unix)]
    b.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    b.tempfile_in(dir)
}

/// Checks, before any expensive work, that `path` can be written: it is not a
/// folder, its folder exists, and a file can be created there (a temporary
/// file is created and removed again).
pub fn check_writable(path: &Path) -> Result<()> {
    let dir = target_dir(path)?;
    temp_in(dir).map_err(|e| output_error(path, e))?;
    Ok(())
}

/// Writes `bytes` to `path` atomically. A file replaced keeps its permissions.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let fail = |e: &dyn std::fmt::Display| output_error(path, e);
    let dir = target_dir(path)?;
    let mut tmp = temp_in(dir).map_err(|e| fail(&e))?;
    if let Ok(meta) = std::fs::metadata(path) {
        tmp.as_file().set_permissions(meta.permissions()).map_err(|e| fail(&e))?;
    }
    tmp.write_all(bytes).map_err(|e| fail(&e))?;
    tmp.as_file().sync_all().map_err(|e| fail(&e))?;
    tmp.persist(path).map_err(|e| fail(&e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_replaces_without_leaving_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(names(dir.path()), ["a.txt"]);
    }

    #[cfg(unix)]
    #[test]
    fn new_files_get_the_permissions_file_create_gives() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let ours = dir.path().join("ours");
        let std_made = dir.path().join("std");
        write_atomic(&ours, b"x").unwrap();
        std::fs::File::create(&std_made).unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&ours), mode(&std_made));
        // A replaced file keeps the permissions its owner gave it.
        std::fs::set_permissions(&ours, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&ours, b"y").unwrap();
        assert_eq!(mode(&ours), 0o640);
    }

    #[test]
    fn unwritable_targets_are_output_errors_and_leave_nothing() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("file"), b"").unwrap();
        for (target, says) in [
            (dir.path().join("missing/a.png"), "does not exist"),
            (dir.path().join("file/a.png"), "is not a folder"),
            (dir.path().to_path_buf(), "is a directory"),
        ] {
            for r in [check_writable(&target), write_atomic(&target, b"x")] {
                let e = r.unwrap_err();
                assert_eq!(e.exit_code(), 1, "{e}");
                let msg = e.to_string();
                assert!(msg.contains(says), "{msg}");
                assert!(!msg.contains(".rtow-"), "temporary name leaked: {msg}");
            }
        }
        assert_eq!(names(dir.path()), ["file"]);
    }
}
