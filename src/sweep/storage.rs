//! The files of sweeps and fits: written whole or not at all (through a
//! temporary name and a rename), and an error that names the file and what
//! was being done to it.

use std::path::{Path, PathBuf};

/// A file or directory that could not be read or written.
#[derive(Debug, thiserror::Error)]
#[error("{action} {}: {source}", path.display())]
pub struct FileError {
    /// What was being done (`writing`, `cannot create`, …).
    pub action: &'static str,
    /// The file or directory.
    pub path: PathBuf,
    /// What the system said.
    pub source: std::io::Error,
}

/// A [`FileError`] for `action` on `path`, from the system's error.
pub fn file(action: &'static str, path: &Path) -> impl FnOnce(std::io::Error) -> FileError {
    let path = path.to_path_buf();
    move |source| FileError {
        action,
        path,
        source,
    }
}

/// `NAME.rrd` → `NAME.rrd.part`.
pub fn part_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".part");
    PathBuf::from(s)
}

/// Writes `bytes` to `path` through `path.part` and a rename, so that
/// `path` is either absent or whole (a sweep's point files: a `.part` left
/// behind marks one cut off).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_through(&part_path(path), path, bytes)
}

/// Writes `bytes` to `path` through a temporary name of this process's, for
/// a file that several processes (shards) may write at once, all the same
/// bytes: `path.part.PID`.
pub fn write_shared(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    let mut tmp = part_path(path).into_os_string();
    tmp.push(format!(".{}", std::process::id()));
    write_through(Path::new(&tmp), path, bytes)
}

fn write_through(tmp: &Path, path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    std::fs::write(tmp, bytes).map_err(file("writing", tmp))?;
    std::fs::rename(tmp, path).map_err(file("renaming into place", tmp))
}
