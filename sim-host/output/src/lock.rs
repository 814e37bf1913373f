//! One writer for a resumable run's state: an exclusive OS lock (`flock`) on a file, held for
//! as long as the [`WriterLock`] lives and released by the OS when its process ends, however it
//! ends (a kill, a Slurm time limit). A second run on the same state is refused with a message
//! that names the process holding it, from Linux's `/proc/locks`, where it can be told.
//!
//! The campaign locks its journal with it ([`WriterLock::take`]: the state's own file, left
//! as it is); the optimiser its checkpoint's lock file, `dem intrude` and `dem lammps` a lock
//! file in their work folder ([`WriterLock::take_recorded`]: a file of its own that records
//! the holder's process and machine, for a holder on another node of a shared file system).
//! The optimiser's lock file is `checkpoint.jsonl.lock`: the checkpoint itself is rewritten by
//! renaming a new file over it, which a lock on the old file would not follow.

use std::fs::{File, OpenOptions, TryLockError};
use std::path::{Path, PathBuf};

/// An exclusive lock on a run's state file.
#[derive(Debug)]
pub struct WriterLock {
    /// Kept open: closing it releases the lock.
    _file: File,
    path: PathBuf,
}

/// Why a lock could not be taken.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LockError {
    /// Another process holds it: `holder` names it when it can be told (`process PID (its
    /// command line)`), otherwise `another process`.
    Held {
        /// The file locked.
        path: PathBuf,
        /// Who holds it.
        holder: String,
    },
    /// The file cannot be opened or locked.
    Io {
        /// The file.
        path: PathBuf,
        /// The OS's reason.
        reason: String,
    },
}

impl std::fmt::Display for LockError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Held { path, holder } => write!(
                f,
                "{} is locked by {holder}: one run writes this state at a time (wait for it, \
                 or stop it)",
                path.display()
            ),
            Self::Io { path, reason } => write!(f, "cannot lock {}: {reason}", path.display()),
        }
    }
}

impl std::error::Error for LockError {}

/// Whether `file` is still the file at `path` (same device and inode).
fn same_file(file: &std::fs::File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

impl WriterLock {
    /// Takes the lock on `path`, creating the file (empty) when it does not exist; an existing
    /// file's contents are left as they are.
    pub fn take(path: &Path) -> Result<Self, LockError> {
        let io = |e: std::io::Error| LockError::Io {
            path: path.to_path_buf(),
            reason: e.to_string(),
        };
        let file = OpenOptions::new()
            .read(true)
            .append(true)
            .create(true)
            .open(path)
            .map_err(io)?;
        match file.try_lock() {
            // Locked, but a holder that removes its lock file when done may have removed this
            // one as it was opened: then the path is another file (or none), whose lock is
            // what counts. Refused as held, so two writers never run on two files.
            Ok(()) if !same_file(&file, path) => Err(LockError::Held {
                path: path.to_path_buf(),
                holder: "another process, which has just released it (try again)".into(),
            }),
            Ok(()) => Ok(Self {
                _file: file,
                path: path.to_path_buf(),
            }),
            Err(TryLockError::WouldBlock) => Err(LockError::Held {
                path: path.to_path_buf(),
                holder: holder(&file).unwrap_or_else(|| "another process".into()),
            }),
            Err(TryLockError::Error(e)) => Err(io(e)),
        }
    }

    /// Takes the lock on `path`, a lock file of its own (not the state itself), and records
    /// in it who holds it: `process PID on HOST (COMMAND)`. A second writer is refused naming
    /// the holder from `/proc/locks` where the kernel lists it, else from that record (a
    /// holder on another machine of a shared file system, whose locks this kernel does not
    /// list with a process).
    pub fn take_recorded(path: &Path) -> Result<Self, LockError> {
        match Self::take(path) {
            Ok(lock) => {
                use std::io::Write;
                let record = format!("{}\n", describe(&std::process::id().to_string()));
                let mut f = &lock._file;
                f.set_len(0)
                    .and_then(|()| f.write_all(record.as_bytes()))
                    .map_err(|e| LockError::Io {
                        path: path.to_path_buf(),
                        reason: e.to_string(),
                    })?;
                Ok(lock)
            }
            Err(LockError::Held { path, holder }) if holder == "another process" => {
                let record = std::fs::read_to_string(&path).unwrap_or_default();
                let record = record.trim();
                Err(LockError::Held {
                    holder: if record.is_empty() {
                        holder
                    } else {
                        format!("{record}, by its record")
                    },
                    path,
                })
            }
            Err(e) => Err(e),
        }
    }

    /// The file locked.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether a process holds the lock on `path` now (a file that does not exist is not
    /// locked). For a status display: by the time it is shown, the answer may have changed.
    pub fn is_held(path: &Path) -> bool {
        File::open(path).is_ok_and(|f| matches!(f.try_lock_shared(), Err(TryLockError::WouldBlock)))
    }
}

/// The process holding a lock on `file`'s inode, from `/proc/locks` (Linux), with its command
/// line: `process 1234 (sandjumper optimize ...)`. `None` where it cannot be told (another
/// system, or a filesystem whose locks the kernel does not list with a local process).
fn holder(file: &File) -> Option<String> {
    use std::os::unix::fs::MetadataExt;
    let inode = file.metadata().ok()?.ino();
    let locks = std::fs::read_to_string("/proc/locks").ok()?;
    // "1: FLOCK  ADVISORY  WRITE 1234 00:2e:5678 0 EOF": the pid, then MAJOR:MINOR:INODE.
    let pid = locks.lines().find_map(|line| {
        let fields: Vec<&str> = line.split_whitespace().collect();
        let at = fields.iter().position(|f| *f == "FLOCK")?;
        let pid = fields.get(at + 3)?;
        let id = fields.get(at + 4)?;
        (id.rsplit(':').next()?.parse::<u64>().ok()? == inode).then(|| pid.to_string())
    })?;
    Some(describe(&pid))
}

/// This machine's name (Linux's `/proc/sys/kernel/hostname`, else `HOSTNAME`), `None` where
/// neither tells it.
fn host_name() -> Option<String> {
    crate::folder::kernel_host_name().or_else(|| {
        std::env::var("HOSTNAME")
            .ok()
            .map(|h| h.trim().to_string())
            .filter(|h| !h.is_empty())
    })
}

/// `process PID on HOST (COMMAND)` for a process of this machine.
fn describe(pid: &str) -> String {
    let command = std::fs::read(format!("/proc/{pid}/cmdline"))
        .ok()
        .map(|c| {
            String::from_utf8_lossy(&c)
                .split('\0')
                .filter(|w| !w.is_empty())
                .collect::<Vec<_>>()
                .join(" ")
        })
        .filter(|c| !c.is_empty());
    let host = host_name().map_or(String::new(), |h| format!(" on {h}"));
    match command {
        Some(c) => format!("process {pid}{host} ({c})"),
        None => format!("process {pid}{host}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_writer_is_refused_naming_the_holder_until_the_first_lets_go() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("state.jsonl");
        std::fs::write(&path, "kept\n").unwrap();
        let first = WriterLock::take(&path).unwrap();
        assert!(WriterLock::is_held(&path));
        // flock locks belong to the open file: a second open in this process is refused too.
        match WriterLock::take(&path) {
            Err(LockError::Held { holder, .. }) => {
                if Path::new("/proc/locks").exists() {
                    assert!(
                        holder.starts_with(&format!("process {} on ", std::process::id())),
                        "{holder}"
                    );
                }
            }
            other => panic!("{other:?}"),
        }
        drop(first);
        assert!(!WriterLock::is_held(&path));
        let again = WriterLock::take(&path).unwrap();
        assert_eq!(again.path(), path);
        // The file's contents are the state's: never touched.
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "kept\n");
    }

    #[test]
    fn a_missing_file_is_created_and_an_unwritable_place_is_an_io_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("new.lock");
        assert!(!WriterLock::is_held(&path));
        let _lock = WriterLock::take(&path).unwrap();
        assert!(path.exists());
        let nowhere = dir.path().join("no/such/folder/x.lock");
        assert!(matches!(
            WriterLock::take(&nowhere),
            Err(LockError::Io { .. })
        ));
    }

    #[test]
    fn a_recorded_lock_names_its_holder_even_where_the_kernel_cannot() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.lock");
        std::fs::write(&path, "a stale record of an earlier run\n").unwrap();
        let first = WriterLock::take_recorded(&path).unwrap();
        let record = std::fs::read_to_string(&path).unwrap();
        let me = format!("process {} on ", std::process::id());
        assert!(record.starts_with(&me), "{record}");
        match WriterLock::take_recorded(&path) {
            Err(LockError::Held { holder, .. }) => assert!(holder.starts_with(&me), "{holder}"),
            other => panic!("{other:?}"),
        }
        drop(first);
        // Free again: taken, and the record is the new holder's.
        let _again = WriterLock::take_recorded(&path).unwrap();
        assert!(std::fs::read_to_string(&path).unwrap().starts_with(&me));
    }
}
