//! Output directories that appear complete or not at all.
//!
//! [`StagedDir::create`] makes a hidden staging directory `.<name>.partial-XXXXXX` beside the
//! target (same parent, so the final rename is atomic on one filesystem); the caller writes
//! every file into [`StagedDir::path`]; [`StagedDir::commit`] renames it onto the target. If
//! the program fails or is interrupted first, the target is untouched and the staging
//! directory is removed (on error) or left under its `.partial-` name, never as if complete.
//! The next run into the same target names such a leftover of a killed run
//! ([`unfinished_beside`]: its marker gives the process and the machine) and leaves it.
//!
//! An existing target is replaced only if it is empty or was itself written by sandjumper
//! (it holds the [`MARKER_FILE`]); any other non-empty directory is refused, so a mistyped
//! `--out ~` can never delete anything.

use std::fmt;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// File written into every output directory; its presence allows replacing that directory.
pub const MARKER_FILE: &str = ".sandjumper-output";

/// An output directory could not be prepared or written.
#[derive(Debug)]
pub struct OutputError {
    /// The path concerned.
    pub path: PathBuf,
    /// What was being done, e.g. "create the output directory".
    pub action: String,
    /// Why it failed.
    pub reason: String,
}

/// An output folder that cannot be prepared or written is the user's to mend (exit 2): a
/// path given where a folder cannot go, a folder that is not ours, a full disk.
impl crate::Blamed for OutputError {
    fn blame(&self) -> crate::Blame {
        crate::Blame::Input
    }
}

impl fmt::Display for OutputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "cannot {} `{}`: {}",
            self.action,
            self.path.display(),
            self.reason
        )
    }
}

impl std::error::Error for OutputError {}

impl OutputError {
    /// Build from an I/O error.
    pub fn io(path: &Path, action: &str, err: &io::Error) -> Self {
        Self {
            path: path.to_path_buf(),
            action: action.to_string(),
            reason: err.to_string(),
        }
    }
}

/// An output directory being written: files go into a staging directory until [`commit`].
///
/// [`commit`]: StagedDir::commit
#[derive(Debug)]
pub struct StagedDir {
    target: PathBuf,
    staging: Option<tempfile::TempDir>,
}

fn dir_is_replaceable(target: &Path) -> Result<bool, OutputError> {
    let mut entries = fs::read_dir(target)
        .map_err(|e| OutputError::io(target, "read the output directory", &e))?;
    if entries.next().is_none() {
        return Ok(true);
    }
    Ok(target.join(MARKER_FILE).is_file())
}

impl StagedDir {
    /// Check that `target` can be (re)written and create its staging directory. Parent
    /// directories are created as needed. Fails, with the path and the reason, if the target
    /// is a file, a non-empty directory not written by sandjumper, or not writable.
    pub fn create(target: &Path) -> Result<Self, OutputError> {
        if target.as_os_str().is_empty() {
            return Err(OutputError {
                path: target.to_path_buf(),
                action: "use the output directory".into(),
                reason: "the path is empty".into(),
            });
        }
        let name = target
            .file_name()
            .ok_or_else(|| OutputError {
                path: target.to_path_buf(),
                action: "use the output directory".into(),
                reason: "the path has no final component (name a directory, e.g. out/jump)".into(),
            })?
            .to_string_lossy()
            .into_owned();
        if target.exists() {
            if !target.is_dir() {
                return Err(OutputError {
                    path: target.to_path_buf(),
                    action: "use the output directory".into(),
                    reason: "it exists and is not a directory".into(),
                });
            }
            if !dir_is_replaceable(target)? {
                return Err(OutputError {
                    path: target.to_path_buf(),
                    action: "replace the output directory".into(),
                    reason: format!(
                        "it is not empty and was not written by sandjumper (no {MARKER_FILE}); \
                         choose a new directory or empty it"
                    ),
                });
            }
        }
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        fs::create_dir_all(&parent).map_err(|e| OutputError {
            path: target.to_path_buf(),
            action: "create the output directory".into(),
            reason: format!("its parent `{}` cannot be created: {e}", parent.display()),
        })?;
        // Nothing lost silently: the partial output of an earlier run into this target that was
        // killed (no chance to clean up) is named, and left as it is.
        for unfinished in unfinished_beside(target) {
            crate::progress::note(&format!(
                "note: {} is the partial output of an earlier run into {} whose process is gone \
                 (killed?); it is left as it is: look inside, or remove it",
                unfinished.display(),
                target.display()
            ));
        }
        let staging = tempfile::Builder::new()
            .prefix(&format!(".{name}.partial-"))
            .tempdir_in(&parent)
            .map_err(|e| OutputError::io(target, "write the output directory", &e))?;
        fs::write(
            staging.path().join(MARKER_FILE),
            format!(
                "written by the sandjumper CLI (process {} on {})\n",
                std::process::id(),
                this_host()
            ),
        )
        .map_err(|e| OutputError::io(target, "write the output directory", &e))?;
        Ok(Self {
            target: target.to_path_buf(),
            staging: Some(staging),
        })
    }

    /// Where to write files now (the staging directory).
    pub fn path(&self) -> &Path {
        self.staging
            .as_ref()
            .map_or(self.target.as_path(), |s| s.path())
    }

    /// The directory the files will be in after [`StagedDir::commit`].
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Path of a file inside the staging directory.
    pub fn file(&self, name: &str) -> PathBuf {
        self.path().join(name)
    }

    /// Write a text file into the staging directory.
    pub fn write_text(&self, name: &str, text: &str) -> Result<(), OutputError> {
        let path = self.file(name);
        fs::write(&path, text).map_err(|e| OutputError::io(&self.target.join(name), "write", &e))
    }

    /// Move the finished directory into place (replacing a previous sandjumper output there).
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        let Some(staging) = self.staging.take() else {
            return Ok(self.target.clone());
        };
        let target = self.target.clone();
        let staged = staging.keep();
        let fail = |action: &str, e: &io::Error| {
            let _ = fs::remove_dir_all(&staged);
            OutputError::io(&target, action, e)
        };
        let mut old = None;
        if target.exists() {
            // Checked again: the directory may have changed while we were computing.
            if !dir_is_replaceable(&target)? {
                let _ = fs::remove_dir_all(&staged);
                return Err(OutputError {
                    path: target.clone(),
                    action: "replace the output directory".into(),
                    reason: "it was filled by something else while sandjumper was running".into(),
                });
            }
            let mut aside_name = staged.file_name().unwrap_or_default().to_os_string();
            aside_name.push(".old");
            let aside = staged.with_file_name(aside_name);
            fs::rename(&target, &aside)
                .map_err(|e| fail("move the previous output directory aside", &e))?;
            old = Some(aside);
        }
        if let Err(e) = fs::rename(&staged, &target) {
            if let Some(aside) = &old {
                let _ = fs::rename(aside, &target);
            }
            return Err(fail("move the finished output into place", &e));
        }
        if let Some(aside) = old {
            let _ = fs::remove_dir_all(aside);
        }
        Ok(target)
    }
}

/// This machine's name as the kernel has it (`/proc/sys/kernel/hostname`), `None` where it
/// cannot be read.
pub(crate) fn kernel_host_name() -> Option<String> {
    fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .ok()
        .filter(|h| !h.is_empty())
}

/// This machine's name (`/proc/sys/kernel/hostname`), or `unknown`.
fn this_host() -> String {
    kernel_host_name().unwrap_or_else(|| "unknown".into())
}

/// Remove a finished run's work folder `work` (its writer's lock file inside it): renamed
/// aside first, so a new run of the same output that starts the moment the lock goes makes a
/// fresh folder of that name, which this never touches. Best effort: a folder that cannot be
/// renamed or removed is left.
pub fn remove_work_dir(work: &Path) {
    let mut done = work.as_os_str().to_os_string();
    done.push(format!(".done-{}", std::process::id()));
    if fs::rename(work, &done).is_ok() {
        let _ = fs::remove_dir_all(&done);
    }
}

/// Who wrote the output folder (or staging folder) `dir`: its marker's text, `written by the
/// sandjumper CLI (process PID on HOST)`; `None` where it has no readable marker.
pub fn written_by(dir: &Path) -> Option<String> {
    fs::read_to_string(dir.join(MARKER_FILE))
        .ok()
        .map(|t| t.trim().to_string())
}

/// The staging directories beside `target` (`.<name>.partial-*`) of earlier runs on this
/// machine whose process is gone: a run killed before it could commit or clean up (a Slurm
/// job past its time, `kill -9`). A staging directory of a live process, of another machine
/// (a cluster's shared filesystem) or of unknown origin is not one of them.
pub fn unfinished_beside(target: &Path) -> Vec<PathBuf> {
    let (Some(parent), Some(name)) = (target.parent(), target.file_name()) else {
        return Vec::new();
    };
    let parent = if parent.as_os_str().is_empty() {
        Path::new(".")
    } else {
        parent
    };
    let prefix = format!(".{}.partial-", name.to_string_lossy());
    // Whose process is gone can be told only on a known machine with a process table.
    let host = this_host();
    if host == "unknown" || !Path::new("/proc/self").exists() {
        return Vec::new();
    }
    let Ok(entries) = fs::read_dir(parent) else {
        return Vec::new();
    };
    let mut found: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .map(|n| n.to_string_lossy())
                .is_some_and(|n| n.starts_with(&prefix) && !n.ends_with(".old"))
        })
        .filter(|p| {
            let Some(marker) = written_by(p) else {
                return false;
            };
            // "... (process PID on HOST)"
            let Some(rest) = marker.split("(process ").nth(1) else {
                return false;
            };
            let mut words = rest.trim_end().trim_end_matches(')').split(" on ");
            let (Some(pid), Some(on)) = (words.next(), words.next()) else {
                return false;
            };
            on == host && pid.parse::<u32>().is_ok() && !Path::new("/proc").join(pid).exists()
        })
        .collect();
    found.sort();
    found
}

/// Write records (with a header, even when there are none) as CSV to `path`.
pub fn write_csv<T: serde::Serialize>(
    path: &Path,
    records: &[T],
    header: &[&str],
) -> Result<(), String> {
    let mut w = csv::Writer::from_path(path)
        .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    if records.is_empty() {
        w.write_record(header)
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    }
    for r in records {
        w.serialize(r)
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    }
    w.flush()
        .map_err(|e| format!("cannot write `{}`: {e}", path.display()))
}

/// Write `data` (row-major, `shape`) as a float64 `.npy` array (NPY format 1.0: the magic
/// string, a header dict padded so the data starts on a 64-byte boundary, then the values
/// little-endian). Written here rather than through a crate: the format's writer is a dozen
/// lines, while the crates that also read it pull a Python-literal parser into every build.
pub fn write_npy(path: &Path, shape: &[u64], data: Vec<f64>) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("cannot write `{}`: {e}", path.display());
    let count = shape.iter().try_fold(1u64, |n, &d| n.checked_mul(d));
    if count != Some(data.len() as u64) {
        let count = count.map_or("more than 2^64".into(), |n| n.to_string());
        return Err(format!(
            "cannot write `{}`: shape {shape:?} holds {count} values, not {}",
            path.display(),
            data.len()
        ));
    }
    let dims = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(u64::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {dims}, }}");
    // magic (6) + version (2) + header length (2) + header + '\n', a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    header.push('\n');
    let header_len = u16::try_from(header.len()).map_err(|_| err(&"the shape is too long"))?;
    let write = || -> io::Result<()> {
        use io::Write;
        let mut w = io::BufWriter::new(fs::File::create(path)?);
        w.write_all(b"\x93NUMPY\x01\x00")?;
        w.write_all(&header_len.to_le_bytes())?;
        w.write_all(header.as_bytes())?;
        for v in &data {
            w.write_all(&v.to_le_bytes())?;
        }
        w.flush()
    };
    write().map_err(|e| err(&e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_files_read_back_with_an_independent_reader() {
        let dir = tempfile::tempdir().unwrap();
        for shape in [vec![5u64], vec![2, 3], vec![0], vec![3, 1, 2]] {
            let n: u64 = shape.iter().product();
            let data: Vec<f64> = (0..n).map(|i| i as f64 * 0.5 - 1.25).collect();
            let path = dir.path().join("a.npy");
            write_npy(&path, &shape, data.clone()).unwrap();
            let bytes = fs::read(&path).unwrap();
            let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
            assert_eq!(npy.shape(), &shape[..]);
            let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
            assert_eq!(
                (10 + header_len) % 64,
                0,
                "data starts on a 64-byte boundary"
            );
            assert_eq!(bytes.len(), 10 + header_len + 8 * n as usize);
            let back: Vec<f64> = npy.into_vec().unwrap();
            assert_eq!(back, data);
        }
        let bad = write_npy(&dir.path().join("b.npy"), &[2, 2], vec![1.0; 3]).unwrap_err();
        assert!(bad.contains("holds 4 values, not 3"), "{bad}");
    }

    #[test]
    fn the_partial_output_of_a_killed_run_is_found_and_a_live_ones_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("jump");
        let host = this_host();
        let partial = |suffix: &str, pid: u64, on: &str| {
            let p = dir.path().join(format!(".jump.partial-{suffix}"));
            fs::create_dir(&p).unwrap();
            fs::write(
                p.join(MARKER_FILE),
                format!("written by the sandjumper CLI (process {pid} on {on})\n"),
            )
            .unwrap();
            p
        };
        // Above any pid_max (2^22): a process that cannot be running.
        let killed = partial("aaaaaa", 99_999_999, &host);
        partial("bbbbbb", u64::from(std::process::id()), &host); // this one: alive
        partial("cccccc", 99_999_999, "another-node"); // a shared filesystem's other machine
        fs::create_dir(dir.path().join(".jump.partial-dddddd")).unwrap(); // no marker
        partial("eeeeee", 99_999_999, &host); // of another target
        fs::rename(
            dir.path().join(".jump.partial-eeeeee"),
            dir.path().join(".other.partial-eeeeee"),
        )
        .unwrap();
        assert_eq!(unfinished_beside(&target), vec![killed.clone()]);
        // A run into the target names it and leaves it; its own staging directory is not one.
        let staged = StagedDir::create(&target).unwrap();
        assert!(killed.is_dir());
        assert_eq!(unfinished_beside(&target), vec![killed.clone()]);
        staged.commit().unwrap();
        assert!(killed.is_dir());
    }

    #[test]
    fn nothing_appears_until_commit_and_then_everything_does() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("a/b/run");
        let staged = StagedDir::create(&target).unwrap();
        staged.write_text("x.txt", "1").unwrap();
        assert!(!target.exists());
        staged.commit().unwrap();
        assert_eq!(fs::read_to_string(target.join("x.txt")).unwrap(), "1");
        // Nothing else left in the parent.
        let names: Vec<_> = fs::read_dir(root.path().join("a/b")).unwrap().collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn dropped_stage_leaves_no_trace() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("run");
        {
            let staged = StagedDir::create(&target).unwrap();
            staged.write_text("x.txt", "1").unwrap();
        }
        assert_eq!(fs::read_dir(root.path()).unwrap().count(), 0);
    }

    #[test]
    fn replaces_own_output_but_refuses_foreign_directories() {
        let root = tempfile::tempdir().unwrap();
        let target = root.path().join("run");
        let s = StagedDir::create(&target).unwrap();
        s.write_text("old.txt", "old").unwrap();
        s.commit().unwrap();
        let s = StagedDir::create(&target).unwrap();
        s.write_text("new.txt", "new").unwrap();
        s.commit().unwrap();
        assert!(target.join("new.txt").exists() && !target.join("old.txt").exists());

        let foreign = root.path().join("home");
        fs::create_dir(&foreign).unwrap();
        fs::write(foreign.join("thesis.tex"), "precious").unwrap();
        let e = StagedDir::create(&foreign).unwrap_err();
        assert!(e.to_string().contains("not empty"), "{e}");
        assert!(foreign.join("thesis.tex").exists());
    }

    #[test]
    fn a_file_is_not_an_output_directory() {
        let root = tempfile::tempdir().unwrap();
        let file = root.path().join("f");
        fs::write(&file, "").unwrap();
        let e = StagedDir::create(&file).unwrap_err();
        assert!(e.to_string().contains("not a directory"), "{e}");
    }
}
