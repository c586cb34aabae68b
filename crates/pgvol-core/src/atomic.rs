//! Atomic file replacement: readers of `path` see either the old file or the complete new one,
//! never a partial write, and a failed write leaves nothing behind.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use crate::FileError;

/// Temporary files being written, so a signal handler can remove them before the process ends.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes every temporary file a write in progress holds. For a termination handler: the
/// process is about to end, and the files it was replacing stay as they were.
pub fn remove_pending_temporaries() {
    let pending = match PENDING.lock() {
        Ok(p) => p.clone(),
        Err(poisoned) => poisoned.into_inner().clone(),
    };
    for tmp in pending {
        let _ = fs::remove_file(tmp);
    }
}

/// Registers `tmp` as pending for as long as the guard lives.
struct Pending(PathBuf);

impl Pending {
    fn new(tmp: &Path) -> Self {
        if let Ok(mut p) = PENDING.lock() {
            p.push(tmp.to_path_buf());
        }
        Pending(tmp.to_path_buf())
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        if let Ok(mut p) = PENDING.lock() {
            p.retain(|t| t != &self.0);
        }
    }
}

/// Writes `path` by letting `f` fill a temporary file in the same directory (so the final
/// rename cannot cross file systems), flushing and syncing it, then renaming it over `path`.
/// On any failure the temporary file is removed and `path` is left untouched.
pub fn write_atomic(
    path: &Path,
    f: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), FileError> {
    let Some(name) = path.file_name() else {
        return Err(FileError::new(path, "not a file path (no file name)"));
    };
    if path.is_dir() {
        return Err(FileError::new(path, "is a directory, not a file"));
    }
    match fs::metadata(path) {
        // A device or a pipe (`-o /dev/null`, `-o /dev/stdout`) is written in place: renaming a
        // file over it would replace the device node itself.
        Ok(meta) if !meta.is_file() => return write_in_place(path, f),
        // Through a symbolic link, replace the file it points to and keep the link.
        Ok(_) if fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) => {
            let target = fs::canonicalize(path)
                .map_err(|e| FileError::new(path, format!("cannot resolve the link: {e}")))?;
            return write_atomic(&target, f);
        }
        _ => {}
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    // The counter keeps concurrent writers in one process from sharing a temporary name.
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = dir.join(format!(
        ".{}.{}.{n}.tmp",
        name.to_string_lossy(),
        std::process::id()
    ));

    let _pending = Pending::new(&tmp);
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(|e| {
            FileError::new(
                path,
                format!("cannot create temporary file '{}': {e}", tmp.display()),
            )
        })?;
    // A replaced file keeps its permissions: an executable script or a shared group file stays so.
    if let Ok(meta) = fs::metadata(path) {
        let _ = file.set_permissions(meta.permissions());
    }
    let result = fill_and_sync(file, f)
        .map_err(|e| FileError::new(path, format!("write failed: {e}")))
        .and_then(|()| {
            fs::rename(&tmp, path).map_err(|e| {
                FileError::new(path, format!("cannot move finished file into place: {e}"))
            })
        });
    match result {
        Ok(()) => {
            sync_dir(&dir);
            Ok(())
        }
        Err(e) => {
            let _ = fs::remove_file(&tmp);
            Err(e)
        }
    }
}

fn write_in_place(
    path: &Path,
    f: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<(), FileError> {
    let file = OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(|e| FileError::new(path, format!("cannot open for writing: {e}")))?;
    let mut w = BufWriter::new(file);
    f(&mut w)
        .and_then(|()| w.flush())
        .map_err(|e| FileError::new(path, format!("write failed: {e}")))
}

fn fill_and_sync(file: File, f: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    let mut w = BufWriter::new(file);
    f(&mut w)?;
    let file = w.into_inner().map_err(|e| e.into_error())?;
    file.sync_all()
}

/// Makes the rename itself durable where the platform allows; failure only weakens durability,
/// never correctness, so it is ignored.
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Removing pending temporaries reaches every write in the process: the tests that write
    /// take turns.
    static SERIAL: Mutex<()> = Mutex::new(());

    fn turn() -> std::sync::MutexGuard<'static, ()> {
        SERIAL.lock().unwrap_or_else(|e| e.into_inner())
    }

    #[test]
    fn a_termination_mid_write_removes_the_temporary_and_keeps_the_old_file() {
        let _turn = turn();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        fs::write(&path, b"old").unwrap();
        let (started, wait) = std::sync::mpsc::channel();
        let (resume, go) = std::sync::mpsc::channel::<()>();
        let writer = {
            let path = path.clone();
            std::thread::spawn(move || {
                write_atomic(&path, |w| {
                    w.write_all(b"partial")?;
                    started.send(()).unwrap();
                    go.recv().unwrap();
                    Ok(())
                })
            })
        };
        wait.recv().unwrap();
        let temporaries = || {
            fs::read_dir(dir.path())
                .unwrap()
                .filter(|e| {
                    e.as_ref()
                        .unwrap()
                        .file_name()
                        .to_string_lossy()
                        .ends_with(".tmp")
                })
                .count()
        };
        assert_eq!(temporaries(), 1);
        remove_pending_temporaries();
        assert_eq!(temporaries(), 0);
        resume.send(()).unwrap();
        // The finished file can no longer be moved into place: the old one stays.
        assert!(writer.join().unwrap().is_err());
        assert_eq!(fs::read(&path).unwrap(), b"old");
        assert_eq!(temporaries(), 0);
    }

    #[test]
    fn a_failed_write_keeps_the_old_file_and_leaves_no_temporary() {
        let _turn = turn();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        fs::write(&path, b"old").unwrap();
        let e = write_atomic(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("disk full"))
        })
        .unwrap_err();
        assert!(e.problem.contains("disk full"), "{e}");
        assert_eq!(fs::read(&path).unwrap(), b"old");
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn a_replaced_file_keeps_its_mode() {
        let _turn = turn();
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.sh");
        fs::write(&path, b"old").unwrap();
        fs::set_permissions(&path, fs::Permissions::from_mode(0o751)).unwrap();
        write_atomic(&path, |w| w.write_all(b"new")).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        let mode = fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o751);
    }
}
