//! Crash-safe file replacement: write to a temporary sibling, sync, rename.

use crate::IoError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes `path` atomically: `f` fills a buffered temporary file in the same directory, which is
/// flushed, synced to disk and renamed over `path`. On any error the temporary file is removed
/// and `path` is left untouched.
pub fn atomic_write<F>(path: &Path, f: F) -> Result<(), IoError>
where
    F: FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
{
    let tmp = temp_path(path);
    let result = write_then_rename(path, &tmp, f);
    if result.is_err() {
        // Best effort: the temporary may not exist if creating it was what failed.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn write_then_rename<F>(path: &Path, tmp: &Path, f: F) -> Result<(), IoError>
where
    F: FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
{
    // The error names `path`, the file the caller asked for, not the temporary name.
    let file = File::create(tmp).map_err(|e| IoError::io(path, e))?;
    let mut writer = BufWriter::with_capacity(1 << 20, file);
    f(&mut writer).map_err(|e| IoError::io(path, e))?;
    writer.flush().map_err(|e| IoError::io(path, e))?;
    let file = writer
        .into_inner()
        .map_err(|e| IoError::io(path, e.into_error()))?;
    file.sync_all().map_err(|e| IoError::io(path, e))?;
    drop(file);
    std::fs::rename(tmp, path).map_err(|e| IoError::io(path, e))
}

/// `dir/.name.tmp<pid>`: hidden, in the same directory so the rename stays on one file system.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".to_string());
    let tmp_name = format!(".{name}.tmp{}", std::process::id());
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.join(tmp_name),
        _ => PathBuf::from(tmp_name),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        atomic_write(&p, |w| w.write_all(b"one")).unwrap();
        atomic_write(&p, |w| w.write_all(b"two")).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn error_leaves_target_and_removes_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        atomic_write(&p, |w| w.write_all(b"keep")).unwrap();
        let err = atomic_write(&p, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("a.txt"), "{err}");
        assert_eq!(std::fs::read(&p).unwrap(), b"keep");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_failure_to_create_names_the_final_file_not_the_temporary() {
        let dir = tempfile::tempdir().unwrap();
        // A regular file where the directory should be: creating anything inside it fails,
        // for root too.
        let blocker = dir.path().join("frames");
        std::fs::write(&blocker, b"").unwrap();
        let p = blocker.join("surface_0001.ply");
        let err = atomic_write(&p, |w| w.write_all(b"x")).unwrap_err();
        let msg = err.to_string();
        assert!(msg.starts_with(&format!("{}: ", p.display())), "{msg}");
        assert!(!msg.contains(".surface_0001.ply.tmp"), "{msg}");
    }
}
