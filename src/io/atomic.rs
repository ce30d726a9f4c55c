//! Atomic file replacement, staged transactions of several files, the
//! per-output-name lock, and the error type of the output writers.
//!
//! Every file is written inside a private staging directory of the target
//! directory (`.signorini-stage-…`, a random name created exclusively with
//! mode 0700 by the `tempfile` crate), flushed to disk, then renamed over the
//! target. Nothing is ever created under a predictable name, so a symbolic
//! link planted in the output directory is never followed; a reader (or a
//! crash) sees either the previous complete file or the new complete file.
//! A [`Stage`] commits several files together and, if the run fails later,
//! puts the previous files back.

use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Read, Write};
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

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
    #[error("{}: HDF5 error at {location}: {cause}{}", .path.display(), lock_hint(.cause))]
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

/// The prefix of every staging directory.
pub const STAGE_PREFIX: &str = ".signorini-stage-";

/// The directory holding `path` (`.` for a bare file name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

fn file_name(path: &Path) -> Result<std::ffi::OsString, IoError> {
    path.file_name()
        .map(|n| n.to_os_string())
        .ok_or_else(|| IoError::format(path, "output path has no file name"))
}

fn missing_dir(path: &Path, dir: &Path) -> IoError {
    IoError::io(
        path,
        "cannot write",
        std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!("directory {} does not exist", dir.display()),
        ),
    )
}

/// Creates `path` for writing; fails if anything (a file, a symbolic link)
/// is already there, so a planted link is never followed.
pub fn create_new(path: &Path) -> std::io::Result<File> {
    OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o644)
        .open(path)
}

/// Lets the kernel drop the cached pages of `f`, a complete output file
/// just synced to disk (so they are clean): nothing reads it back, and the
/// pages freed are what the next step's files are written into. Without
/// this each load step's ~150 MB (at 400 k nodes) is new page cache the
/// kernel must find room for, and buffered writes into new pages ran at
/// 200–400 MB/s here instead of 2–3 GB/s into pages just freed. Advice
/// only: errors are ignored.
fn drop_cached(f: &File) {
    use std::os::fd::AsRawFd;
    // SAFETY: posix_fadvise on an open descriptor reads no memory of ours.
    unsafe {
        libc::posix_fadvise(f.as_raw_fd(), 0, 0, libc::POSIX_FADV_DONTNEED);
    }
}

/// fsync a directory; some file systems refuse, and the data itself is
/// already on disk then, so errors are ignored.
fn sync_dir(dir: &Path) {
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
}

/// A set of output files written in a private staging directory of the
/// output directory and moved into place together by [`Stage::commit`].
///
/// Every file a commit replaces is first hard-linked into the staging
/// directory, so that until [`Stage::finish`] the previous files can be put
/// back: dropping an unfinished stage (an error, an early return) restores
/// the output directory to what it held before the run. A process killed
/// mid-run leaves the committed files (each complete) and the staging
/// directory, which the next run of the same name removes
/// ([`remove_stale_stages`]).
pub struct Stage {
    target: PathBuf,
    dir: Option<tempfile::TempDir>,
    /// Files replaced or created by commits, with the backup of the previous
    /// file (None: there was none), in commit order.
    touched: Vec<(PathBuf, Option<PathBuf>)>,
    keep_backups: bool,
}

impl Stage {
    /// A new staging directory in `target` named `PREFIX` + random characters.
    pub fn new(target: &Path, prefix: &str) -> Result<Stage, IoError> {
        if !target.is_dir() {
            return Err(missing_dir(target, target));
        }
        let dir = tempfile::Builder::new()
            .prefix(prefix)
            .tempdir_in(target)
            .map_err(|e| IoError::io(target, "cannot create a staging directory", e))?;
        Ok(Stage {
            target: target.to_path_buf(),
            dir: Some(dir),
            touched: vec![],
            keep_backups: true,
        })
    }

    /// The staging directory.
    pub fn dir(&self) -> &Path {
        self.stage_dir()
    }

    fn stage_dir(&self) -> &Path {
        self.dir.as_ref().map(|d| d.path()).unwrap_or(&self.target)
    }

    /// The staged path of the output file `name`.
    pub fn path(&self, name: &str) -> PathBuf {
        self.stage_dir().join(name)
    }

    /// The final path of the output file `name`.
    pub fn target(&self, name: &str) -> PathBuf {
        self.target.join(name)
    }

    /// Moves the staged files `names` into place (each fsynced first, then
    /// renamed; the directory is fsynced once). A file is replaced by a
    /// rename, so it is never seen half-written. On error the files of this
    /// commit that were already moved are put back.
    pub fn commit(&mut self, names: &[&str]) -> Result<(), IoError> {
        for n in names {
            let staged = self.path(n);
            let f = File::open(&staged)
                .map_err(|e| IoError::io(&self.target(n), "cannot reopen staged file", e))?;
            f.sync_all()
                .map_err(|e| IoError::io(&self.target(n), "cannot sync to disk", e))?;
            drop_cached(&f);
        }
        let before = self.touched.len();
        for n in names {
            if let Err(e) = self.move_into_place(n) {
                self.restore_from(before);
                return Err(e);
            }
        }
        sync_dir(&self.target);
        Ok(())
    }

    fn move_into_place(&mut self, name: &str) -> Result<(), IoError> {
        let fin = self.target(name);
        if !self.keep_backups {
            return std::fs::rename(self.path(name), &fin)
                .map_err(|e| IoError::io(&fin, "cannot rename into place", e));
        }
        let already = self.touched.iter().any(|(p, _)| *p == fin);
        if !already {
            let backup = if std::fs::symlink_metadata(&fin).is_ok() {
                let prev = self.stage_dir().join(".prev");
                if !prev.is_dir() {
                    std::fs::create_dir(&prev)
                        .map_err(|e| IoError::io(&fin, "cannot keep the previous file", e))?;
                }
                let b = prev.join(name);
                // A hard link keeps the previous file in place until the rename.
                if std::fs::hard_link(&fin, &b).is_err() {
                    std::fs::copy(&fin, &b)
                        .map_err(|e| IoError::io(&fin, "cannot keep the previous file", e))?;
                }
                Some(b)
            } else {
                None
            };
            self.touched.push((fin.clone(), backup));
        }
        std::fs::rename(self.path(name), &fin)
            .map_err(|e| IoError::io(&fin, "cannot rename into place", e))
    }

    /// Removes the file `name` of the output directory as part of the
    /// transaction: like a replaced file, it is first kept in `.prev/`
    /// (a hard link), so that a rollback puts it back; [`Stage::finish`]
    /// drops it. A name already committed or removed, or absent, is left.
    pub fn remove(&mut self, name: &str) -> Result<(), IoError> {
        let fin = self.target(name);
        if self.touched.iter().any(|(p, _)| *p == fin) || std::fs::symlink_metadata(&fin).is_err() {
            return Ok(());
        }
        let prev = self.stage_dir().join(".prev");
        if !prev.is_dir() {
            std::fs::create_dir(&prev)
                .map_err(|e| IoError::io(&fin, "cannot keep the previous file", e))?;
        }
        let b = prev.join(name);
        // A rename keeps the file (its inode, its bytes) for a rollback.
        std::fs::rename(&fin, &b)
            .map_err(|e| IoError::io(&fin, "cannot remove the previous run's file", e))?;
        self.touched.push((fin, Some(b)));
        Ok(())
    }

    /// Put back the previous files of every commit from index `from` of
    /// `touched` on (best effort: this runs on an error path).
    fn restore_from(&mut self, from: usize) {
        while self.touched.len() > from {
            let Some((fin, backup)) = self.touched.pop() else {
                break;
            };
            match backup {
                Some(b) => {
                    let _ = std::fs::rename(&b, &fin);
                }
                None => {
                    let _ = std::fs::remove_file(&fin);
                }
            }
        }
        sync_dir(&self.target);
    }

    /// Undo every commit: the output directory holds what it held before.
    pub fn rollback(mut self) {
        self.restore_from(0);
    }

    /// The run is complete: drop the backups and the staging directory.
    pub fn finish(mut self) {
        self.touched.clear();
        if let Some(d) = self.dir.take() {
            let _ = d.close();
        }
    }
}

impl Drop for Stage {
    fn drop(&mut self) {
        if !self.touched.is_empty() {
            self.restore_from(0);
        }
    }
}

/// Removes staging directories `PREFIX` + 6 random characters left in `dir`
/// by a run that was killed (call only while holding the name's lock).
pub fn remove_stale_stages(dir: &Path, prefix: &str) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        let is_stale = name
            .strip_prefix(prefix)
            .is_some_and(|r| r.len() == 6 && r.bytes().all(|b| b.is_ascii_alphanumeric()));
        if is_stale && e.file_type().is_ok_and(|t| t.is_dir()) {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Writes `path` atomically: `f` receives a path in a private staging
/// directory next to `path` and must create and fill that file (closing it
/// before it returns). The file is then fsynced and renamed over `path`, and
/// the directory is fsynced (best effort). If `f` or any later step fails,
/// the staging directory is removed and `path` is left untouched.
///
/// Errors from `f` that name the staged file are rewritten to name `path`.
pub fn write_atomic<F>(path: &Path, f: F) -> Result<(), IoError>
where
    F: FnOnce(&Path) -> Result<(), IoError>,
{
    let name = file_name(path)?;
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(missing_dir(path, &dir));
    }
    // A device or a FIFO at the target (`-o /dev/full`, `--json /dev/stdout`)
    // is never replaced by a file: the rename would unlink the device node
    // (as root, in /dev). A symbolic link is replaced, never followed.
    if let Ok(m) = std::fs::symlink_metadata(path) {
        let t = m.file_type();
        if !t.is_file() && !t.is_symlink() {
            return Err(IoError::format(
                path,
                "exists and is not a regular file (a device, FIFO, socket or directory): give a file name",
            ));
        }
    }
    let mut stage = Stage::new(&dir, STAGE_PREFIX).map_err(|e| e.retarget(&dir, path))?;
    stage.keep_backups = false;
    let tmp = stage.stage_dir().join(&name);
    let result = f(&tmp).and_then(|()| {
        let n = name.to_string_lossy().into_owned();
        if Path::new(&n).file_name() != Some(name.as_os_str()) {
            return Err(IoError::format(path, "output file name is not valid UTF-8"));
        }
        stage.commit(&[&n])
    });
    match result {
        Ok(()) => {
            stage.finish();
            Ok(())
        }
        Err(e) => Err(e.retarget(&tmp, path)),
    }
}

/// Writes `path` atomically through a buffered writer.
pub fn write_atomic_with<F>(path: &Path, f: F) -> Result<(), IoError>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    write_atomic(path, |tmp| {
        let file = create_new(tmp).map_err(|e| IoError::io(path, "cannot create", e))?;
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

/// An advisory lock (`flock`) on `.NAME.lock` in an output directory: one
/// run per output name at a time. The lock file holds the PID of its holder
/// and is removed when the lock is released.
///
/// A lock file is only ever written by the process that created it
/// (`O_CREAT | O_EXCL`): a file found at the lock's name, whatever it is (a
/// hard link to a file elsewhere, a huge file, a FIFO), is opened read-only
/// and not blocking, and of it at most [`LOCK_READ_MAX`] bytes are read, to
/// name its holder. One that nobody holds is stale (its holder died): its
/// name is unlinked while we hold its lock, and a fresh file is created.
pub struct OutputLock {
    path: PathBuf,
    file: Option<File>,
}

/// Bytes of an existing lock file read to name its holder (a PID and a newline).
pub const LOCK_READ_MAX: u64 = 32;

/// Attempts of [`OutputLock::acquire`]: each one that does not end only lost
/// a race with another run that created, took or unlinked the file meanwhile.
const LOCK_ATTEMPTS: usize = 100;

impl OutputLock {
    /// Takes the lock of `name` in `dir` or fails at once, naming the holder.
    pub fn acquire(dir: &Path, name: &str) -> Result<OutputLock, String> {
        let path = dir.join(format!(".{name}.lock"));
        let shown = path.display();
        let same_inode = |file: &File| match (file.metadata(), std::fs::symlink_metadata(&path)) {
            (Ok(a), Ok(b)) => a.ino() == b.ino() && a.dev() == b.dev(),
            _ => false,
        };
        for _ in 0..LOCK_ATTEMPTS {
            match OpenOptions::new()
                .read(true)
                .write(true)
                .create_new(true)
                .mode(0o644)
                .open(&path)
            {
                Ok(mut file) => {
                    // Ours, unless a run that took it for stale holds or
                    // unlinked it between our create and our lock: try again.
                    match file.try_lock() {
                        Ok(()) => {}
                        Err(std::fs::TryLockError::WouldBlock) => continue,
                        Err(std::fs::TryLockError::Error(e)) => {
                            if same_inode(&file) {
                                let _ = std::fs::remove_file(&path);
                            }
                            return Err(format!("{shown}: cannot lock: {e}"));
                        }
                    }
                    if !same_inode(&file) {
                        continue;
                    }
                    let _ = file.write_all(format!("{}\n", std::process::id()).as_bytes());
                    let _ = file.flush();
                    return Ok(OutputLock {
                        path,
                        file: Some(file),
                    });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(format!("{shown}: cannot create the lock file: {e}")),
            }
            // Something is there. Never written to: read-only, not following
            // a symbolic link, not blocking on a FIFO.
            let file = match OpenOptions::new()
                .read(true)
                .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK)
                .open(&path)
            {
                Ok(f) => f,
                // Unlinked by its holder since: try again.
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) if e.raw_os_error() == Some(libc::ELOOP) => {
                    return Err(format!(
                        "{shown}: is a symbolic link; refusing to follow it"
                    ))
                }
                Err(e) => return Err(format!("{shown}: cannot open the lock file: {e}")),
            };
            match file.metadata() {
                Ok(m) if m.is_file() => {}
                Ok(_) => {
                    return Err(format!(
                        "{shown}: is not a regular file (a directory, FIFO, socket or device), so it cannot be the lock of \"{name}\"; remove it"
                    ))
                }
                Err(e) => return Err(format!("{shown}: cannot open the lock file: {e}")),
            }
            match file.try_lock() {
                Ok(()) => {
                    // Stale: unlink the name (only the name: a hard link's
                    // other names keep the file as it was), then create anew.
                    if same_inode(&file) {
                        std::fs::remove_file(&path).map_err(|e| {
                            format!("{shown}: cannot remove the stale lock file: {e}")
                        })?;
                    }
                    continue;
                }
                Err(std::fs::TryLockError::WouldBlock) => {
                    let mut head = Vec::new();
                    let _ = (&file).take(LOCK_READ_MAX).read_to_end(&mut head);
                    let head = String::from_utf8_lossy(&head);
                    let pid = head.lines().next().unwrap_or("").trim();
                    let holder = if !pid.is_empty()
                        && pid.len() < 12
                        && pid.bytes().all(|b| b.is_ascii_digit())
                    {
                        format!("process {pid}")
                    } else {
                        "another process".to_string()
                    };
                    return Err(format!(
                        "{shown}: {holder} is writing the outputs of \"{name}\" in {}; wait for it to end or choose another --out",
                        dir.display()
                    ));
                }
                Err(std::fs::TryLockError::Error(e)) => {
                    return Err(format!("{shown}: cannot lock: {e}"));
                }
            }
        }
        Err(format!(
            "{shown}: cannot lock: the lock file keeps changing"
        ))
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Unlink while still holding the lock, then release it.
        let _ = std::fs::remove_file(&self.path);
        drop(self.file.take());
    }
}

/// HDF5 locks a file while it is open for writing (h5py's `File(..., "a")`,
/// another signorini run): say so, since errno 11 alone does not.
fn lock_hint(cause: &::hdf5::Error) -> &'static str {
    if cause.to_string().contains("unable to lock file") {
        " (is the file open in another program, such as h5py or another signorini run? \
         close it, or run with HDF5_USE_FILE_LOCKING=FALSE if it is only being read)"
    } else {
        ""
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_of_the_same_name_names_the_first_holder() {
        let d = tempfile::tempdir().unwrap();
        let first = OutputLock::acquire(d.path(), "m").unwrap();
        let err = OutputLock::acquire(d.path(), "m").err().unwrap();
        assert!(
            err.contains(&format!("process {}", std::process::id())),
            "{err}"
        );
        drop(first);
        assert!(!d.path().join(".m.lock").exists());
        let again = OutputLock::acquire(d.path(), "m").unwrap();
        drop(again);
    }

    #[test]
    fn a_stale_hard_link_loses_its_name_only() {
        let d = tempfile::tempdir().unwrap();
        let other = d.path().join("other");
        std::fs::write(&other, b"keep me").unwrap();
        let out = d.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::fs::hard_link(&other, out.join(".m.lock")).unwrap();
        let lock = OutputLock::acquire(&out, "m").unwrap();
        assert_eq!(std::fs::read(&other).unwrap(), b"keep me");
        let text = std::fs::read_to_string(out.join(".m.lock")).unwrap();
        assert_eq!(text.trim(), std::process::id().to_string());
        drop(lock);
        assert_eq!(std::fs::read(&other).unwrap(), b"keep me");
    }
}
