//! Atomic file replacement and the error type of the output writers.
//!
//! A file is written under a temporary name in the target directory
//! (`.NAME.tmp-PID-N`), flushed to disk, then renamed over the target. A
//! reader (or a crash) therefore sees either the previous complete file or
//! the new complete file, never a partial one. On error the temporary file
//! is removed.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Errors of the output writers and readers. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// An operating-system error while creating, writing, syncing or renaming.
    #[error("{}: {action}: {cause}", .path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        cause: std::io::Error,
    },
    /// An error reported by the VTK library (encoding or parsing).
    #[error("{}: VTK error: {message}", .path.display())]
    Vtk { path: PathBuf, message: String },
    /// An error reported by the HDF5 library.
    #[error("{}: HDF5 error at {location}: {cause}", .path.display())]
    Hdf5 {
        path: PathBuf,
        location: String,
        cause: ::hdf5::Error,
    },
    /// A group, dataset or attribute that must exist is missing.
    #[error("{}: missing {what}", .path.display())]
    Missing { path: PathBuf, what: String },
    /// Inconsistent or malformed data (wrong lengths, bad indices, bad shape).
    #[error("{}: {message}", .path.display())]
    Format { path: PathBuf, message: String },
}

impl IoError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            IoError::Io { path, .. }
            | IoError::Vtk { path, .. }
            | IoError::Hdf5 { path, .. }
            | IoError::Missing { path, .. }
            | IoError::Format { path, .. } => path,
        }
    }

    pub(crate) fn io(path: &Path, action: &'static str, cause: std::io::Error) -> Self {
        IoError::Io {
            path: path.to_path_buf(),
            action,
            cause,
        }
    }

    pub(crate) fn format(path: &Path, message: impl Into<String>) -> Self {
        IoError::Format {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }

    pub(crate) fn missing(path: &Path, what: impl Into<String>) -> Self {
        IoError::Missing {
            path: path.to_path_buf(),
            what: what.into(),
        }
    }

    /// Rewrites the path of an error that names a temporary file so that it
    /// names the user's target instead (the temporary name means nothing to
    /// the user, and the file no longer exists).
    fn retarget(mut self, tmp: &Path, target: &Path) -> Self {
        let p = match &mut self {
            IoError::Io { path, .. }
            | IoError::Vtk { path, .. }
            | IoError::Hdf5 { path, .. }
            | IoError::Missing { path, .. }
            | IoError::Format { path, .. } => path,
        };
        if p.as_path() == tmp {
            *p = target.to_path_buf();
        }
        self
    }
}

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// The temporary name used for `path`: `.NAME.tmp-PID-N` in the same directory
/// (unique within the process, so concurrent writers of one target do not
/// collide).
pub fn temp_path_for(path: &Path) -> Result<PathBuf, IoError> {
    let name = path
        .file_name()
        .ok_or_else(|| IoError::format(path, "output path has no file name"))?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp-{}-{}", std::process::id(), n));
    Ok(parent_dir(path).join(tmp_name))
}

/// The directory holding `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Writes `path` atomically: `f` receives a temporary path in the same
/// directory and must create and fill that file (closing it before it
/// returns). The file is then fsynced and renamed over `path`, and the
/// directory is fsynced (best effort). If `f` or any later step fails, the
/// temporary file is removed and `path` is left untouched.
///
/// Errors from `f` that name the temporary file are rewritten to name `path`.
pub fn write_atomic<F>(path: &Path, f: F) -> Result<(), IoError>
where
    F: FnOnce(&Path) -> Result<(), IoError>,
{
    let tmp = temp_path_for(path)?;
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(IoError::io(
            path,
            "cannot write",
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("directory {} does not exist", dir.display()),
            ),
        ));
    }
    let result = f(&tmp).and_then(|()| finish(&tmp, path));
    match result {
        Ok(()) => Ok(()),
        Err(e) => {
            // Best effort: the temporary may not exist (f failed before creating it).
            let _ = std::fs::remove_file(&tmp);
            Err(e.retarget(&tmp, path))
        }
    }
}

/// fsync the finished temporary file, rename it into place, fsync the directory.
fn finish(tmp: &Path, path: &Path) -> Result<(), IoError> {
    let file = File::open(tmp).map_err(|e| IoError::io(path, "cannot reopen temporary file", e))?;
    file.sync_all()
        .map_err(|e| IoError::io(path, "cannot sync to disk", e))?;
    drop(file);
    std::fs::rename(tmp, path).map_err(|e| IoError::io(path, "cannot rename into place", e))?;
    // Make the rename durable. Some file systems refuse to fsync a directory;
    // the data itself is already on disk, so ignore that.
    if let Ok(dir) = File::open(parent_dir(path)) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// Writes `path` atomically through a buffered writer.
pub fn write_atomic_with<F>(path: &Path, f: F) -> Result<(), IoError>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    write_atomic(path, |tmp| {
        let file = File::create(tmp).map_err(|e| IoError::io(path, "cannot create", e))?;
        let mut w = BufWriter::new(file);
        f(&mut w).map_err(|e| IoError::io(path, "cannot write", e))?;
        w.flush()
            .map_err(|e| IoError::io(path, "cannot write", e))?;
        Ok(())
    })
}

/// Writes `bytes` to `path` atomically.
pub fn write_atomic_bytes(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}
