//! The search's checkpoint: every evaluation so far, so a search killed at any moment resumes
//! to the same answer.
//!
//! CMA-ES with a fixed seed draws the same candidates in the same order whenever it is told
//! the same values; the optimiser's state (mean, step size, covariance, evolution paths) is a
//! function of the seed and the values told. The checkpoint therefore records, after every
//! generation, the value of each candidate evaluated, keyed by the exact bits of its point; a
//! resumed search replays the generations from the seed, reading recorded values instead of
//! simulating, and reaches the crash point in the optimiser state it had, then goes on.
//!
//! File: a header line (`sandjumper-optimize-checkpoint 1` and the search's settings as
//! JSON), then one line per evaluation, `KEY VALUE` as 16 hex digits each (the 64-bit FNV-1a
//! hash of the point's f64 bits, the fitness's f64 bits). Lines are appended and flushed
//! after every generation; a line cut short by a crash is ignored. A search that is over
//! appends `finished` and its folder's writer (the folder's marker text, [`Checkpoint::finish`])
//! just before it puts its folder in place, then removes the file: one left with that line
//! beside a folder of that writer was killed in between ([`finished_by`]).

use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

const MAGIC: &str = "sandjumper-optimize-checkpoint 1";

/// The start of a finished search's last line ([`Checkpoint::finish`]), before its writer.
const FINISHED: &str = "finished ";

/// The writer [`Checkpoint::finish`] recorded, if the checkpoint at `path` ends with its line:
/// its search was over and putting its folder in place. `None` for a missing or unreadable
/// file, or one that does not end so.
pub fn finished_by(path: &Path) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    text.lines()
        .last()?
        .strip_prefix(FINISHED)
        .map(str::to_string)
}

/// The key of a point: FNV-1a over its coordinates' bits.
pub fn point_key(x: &[f64]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in x {
        for b in v.to_bits().to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// The top-level settings that differ between two settings objects (JSON), in words.
fn differing(recorded: &str, now: &str) -> String {
    let parse = |t: &str| serde_json::from_str::<serde_json::Value>(t).ok();
    match (parse(recorded), parse(now)) {
        (Some(serde_json::Value::Object(a)), Some(serde_json::Value::Object(b))) => {
            let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
            keys.sort();
            keys.dedup();
            let diff: Vec<String> = keys
                .into_iter()
                .filter(|k| a.get(*k) != b.get(*k))
                .map(|k| format!("`{k}`"))
                .collect();
            if diff.is_empty() {
                "settings differ".into()
            } else {
                format!("it differs in {}", diff.join(", "))
            }
        }
        _ => "unreadable settings".into(),
    }
}

/// An open checkpoint: the values recorded so far and the file new ones go to.
#[derive(Debug)]
pub struct Checkpoint {
    path: PathBuf,
    file: File,
    recorded: HashMap<u64, f64>,
    /// Evaluations recorded when it was opened.
    pub resumed_evaluations: usize,
    /// The file's length before [`finish`](Self::finish)'s mark, while it is marked.
    unmarked_len: Option<u64>,
}

impl Checkpoint {
    /// Open `path` for a search with `settings` (JSON): a new file, or an existing one made
    /// with the same settings (resumed). An existing file with other settings is an error
    /// naming the difference's place.
    pub fn open(path: &Path, settings: &str) -> Result<Self, String> {
        let header = format!("{MAGIC} {settings}");
        let mut recorded = HashMap::new();
        if path.exists() {
            let f = File::open(path)
                .map_err(|e| format!("{}: cannot read the checkpoint: {e}", path.display()))?;
            let mut lines = BufReader::new(f).lines();
            let first = lines
                .next()
                .transpose()
                .map_err(|e| format!("{}: cannot read the checkpoint: {e}", path.display()))?
                .unwrap_or_default();
            if !first.starts_with(MAGIC) {
                return Err(format!(
                    "{}: not a sandjumper optimize checkpoint (remove it, or choose another --out)",
                    path.display()
                ));
            }
            if first != header {
                return Err(format!(
                    "{}: this checkpoint was made by a search with other settings ({}); resume \
                     it with the same arguments, or remove it to start afresh",
                    path.display(),
                    differing(first.trim_start_matches(MAGIC).trim(), settings)
                ));
            }
            for line in lines {
                let Ok(line) = line else { break };
                if line.len() != 33 {
                    break;
                }
                let mut it = line.split(' ');
                let (Some(k), Some(v), None) = (it.next(), it.next(), it.next()) else {
                    break;
                };
                let (Ok(k), Ok(v)) = (u64::from_str_radix(k, 16), u64::from_str_radix(v, 16))
                else {
                    break;
                };
                recorded.insert(k, f64::from_bits(v));
            }
            // Rewrite the file without any cut line (into a temporary file renamed over it, so
            // a crash now loses nothing), then append.
            let tmp = path.with_extension("checkpoint-rewrite");
            let mut f = File::create(&tmp)
                .map_err(|e| format!("{}: cannot write the checkpoint: {e}", tmp.display()))?;
            let mut text = format!("{header}\n");
            let mut keys: Vec<_> = recorded.iter().collect();
            keys.sort_by_key(|(k, _)| **k);
            for (k, v) in keys {
                text.push_str(&format!("{k:016x} {:016x}\n", v.to_bits()));
            }
            f.write_all(text.as_bytes())
                .and_then(|()| f.sync_all())
                .and_then(|()| std::fs::rename(&tmp, path))
                .map_err(|e| format!("{}: cannot write the checkpoint: {e}", path.display()))?;
        } else {
            let mut f = File::create(path)
                .map_err(|e| format!("{}: cannot create the checkpoint: {e}", path.display()))?;
            f.write_all(format!("{header}\n").as_bytes())
                .map_err(|e| format!("{}: cannot write the checkpoint: {e}", path.display()))?;
        }
        let file = OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| format!("{}: cannot open the checkpoint: {e}", path.display()))?;
        let resumed_evaluations = recorded.len();
        Ok(Self {
            path: path.to_path_buf(),
            file,
            recorded,
            resumed_evaluations,
            unmarked_len: None,
        })
    }

    /// The recorded value of the point with key `key`.
    pub fn recorded(&self, key: u64) -> Option<f64> {
        self.recorded.get(&key).copied()
    }

    /// Append new evaluations and flush them to the system.
    pub fn append(&mut self, entries: &[(u64, f64)]) -> Result<(), String> {
        let mut text = String::with_capacity(34 * entries.len());
        for &(k, v) in entries {
            if self.recorded.insert(k, v).is_none() {
                text.push_str(&format!("{k:016x} {:016x}\n", v.to_bits()));
            }
        }
        self.file
            .write_all(text.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| {
                format!(
                    "{}: cannot append to the checkpoint: {e}",
                    self.path.display()
                )
            })
    }

    /// Mark the search over, just before its folder is put in place, with `writer`, the text
    /// of that folder's marker (its process and machine): a kill between the folder's rename
    /// and the file's removal leaves a checkpoint [`finished_by`] that writer, beside a folder
    /// whose marker says the same. A search resumed from it reads its evaluations as before
    /// (the line is not one), and drops the line.
    pub fn finish(&mut self, writer: &str) -> Result<(), String> {
        let writer = writer.trim().replace('\n', " ");
        let fail =
            |e: std::io::Error| format!("{}: cannot mark the checkpoint: {e}", self.path.display());
        let before = self.file.metadata().map_err(fail)?.len();
        self.file
            .write_all(format!("{FINISHED}{writer}\n").as_bytes())
            .and_then(|()| self.file.sync_data())
            .map_err(fail)?;
        self.unmarked_len = Some(before);
        Ok(())
    }

    /// Take back [`finish`](Self::finish)'s mark (the folder did not take its place): the
    /// file is cut back to its evaluations, and a later search resumes from it.
    pub fn unfinish(&mut self) -> Result<(), String> {
        let Some(len) = self.unmarked_len.take() else {
            return Ok(());
        };
        self.file
            .set_len(len)
            .and_then(|()| self.file.sync_data())
            .map_err(|e| format!("{}: cannot unmark the checkpoint: {e}", self.path.display()))
    }

    /// Evaluations recorded.
    pub fn len(&self) -> usize {
        self.recorded.len()
    }

    /// Whether none is recorded.
    pub fn is_empty(&self) -> bool {
        self.recorded.is_empty()
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_resume_and_refuse_other_settings() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.ckpt");
        let mut c = Checkpoint::open(&path, "{\"seed\":1}").unwrap();
        let k = point_key(&[0.1, 0.2]);
        assert_ne!(k, point_key(&[0.2, 0.1]));
        c.append(&[(k, -0.0123), (7, 1e3)]).unwrap();
        drop(c);
        // A line cut short by a crash is ignored.
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"00000000000000ab 3ff0").unwrap();
        drop(f);
        let c = Checkpoint::open(&path, "{\"seed\":1}").unwrap();
        assert_eq!(c.resumed_evaluations, 2);
        assert_eq!(c.recorded(k), Some(-0.0123));
        assert_eq!(c.recorded(0xab), None);
        drop(c);
        // Marked finished: told apart, and a resume still reads every evaluation.
        assert_eq!(finished_by(&path), None);
        let mut c = Checkpoint::open(&path, "{\"seed\":1}").unwrap();
        c.finish("written by the sandjumper CLI (process 7 on h)\n")
            .unwrap();
        drop(c);
        assert_eq!(
            finished_by(&path).as_deref(),
            Some("written by the sandjumper CLI (process 7 on h)")
        );
        let mut c = Checkpoint::open(&path, "{\"seed\":1}").unwrap();
        assert_eq!(c.resumed_evaluations, 2);
        assert_eq!(finished_by(&path), None, "a resumed search is not over");
        // A mark taken back (the folder did not take its place): unmarked, and resumed whole.
        c.finish("w").unwrap();
        assert_eq!(finished_by(&path).as_deref(), Some("w"));
        c.unfinish().unwrap();
        assert_eq!(finished_by(&path), None);
        drop(c);
        assert_eq!(
            Checkpoint::open(&path, "{\"seed\":1}")
                .unwrap()
                .resumed_evaluations,
            2
        );
        let e = Checkpoint::open(&path, "{\"seed\":2}").unwrap_err();
        assert!(e.contains("other settings") && e.contains("`seed`"), "{e}");
        std::fs::write(&path, "hello\n").unwrap();
        assert!(
            Checkpoint::open(&path, "{}")
                .unwrap_err()
                .contains("not a sandjumper")
        );
    }
}
