//! Reading input files whole, refusing what is not a regular file: a device (`/dev/zero`), a
//! pipe or a folder never ends or never starts, and would exhaust memory or block.

use std::fs;
use std::path::Path;

use crate::FileError;

/// The bytes of the regular file at `path`.
pub fn read_input(path: &Path) -> Result<Vec<u8>, FileError> {
    let meta =
        fs::metadata(path).map_err(|e| FileError::new(path, format!("cannot read file: {e}")))?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a folder"
        } else {
            "not a regular file (a device or a pipe)"
        };
        return Err(FileError::new(path, format!("cannot read: it is {what}")));
    }
    fs::read(path).map_err(|e| FileError::new(path, format!("cannot read file: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_files_are_read_and_others_refused() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a.obj");
        fs::write(&file, b"v 0 0 0\n").unwrap();
        assert_eq!(read_input(&file).unwrap(), b"v 0 0 0\n");
        let e = read_input(dir.path()).unwrap_err();
        assert!(e.problem.contains("a folder"), "{e}");
        #[cfg(unix)]
        {
            let e = read_input(Path::new("/dev/zero")).unwrap_err();
            assert!(e.problem.contains("not a regular file"), "{e}");
        }
        assert!(read_input(&dir.path().join("missing.obj")).is_err());
    }
}
