//! The campaign's journal: one JSON record per line, appended and flushed to the disk
//! (`fsync`) at every state change. It is the only source of truth: `results.csv`,
//! `documents.jsonl` and `campaign status` are derived from it. A line cut by a crash
//! (power cut, `kill -9`) is dropped and reported when the journal is opened again; any
//! other unreadable line is a corrupt journal (refused).

use std::fs::{File, OpenOptions};
use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::plan::Point;
use super::prepare::Preparation;
use super::result_row::ResultRow;

/// One journal record.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// 0, 1, 2, ... in the file.
    pub seq: u64,
    /// Wall-clock time, s since the Unix epoch.
    pub time: f64,
    /// What happened.
    #[serde(flatten)]
    pub event: Event,
}

/// What happened.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "kebab-case")]
pub enum Event {
    /// The campaign was planned: its file (as text) and its points in run order.
    Planned {
        /// Campaign name.
        name: String,
        /// The campaign file's text.
        file_text: String,
        /// The points.
        points: Vec<Point>,
        /// Link: `sil`, `pil` or a serial port.
        link: String,
    },
    /// A session (run or resume) began.
    SessionStarted {
        /// 1 for `run`, 2.. for each `resume`.
        session: u32,
    },
    /// A point started (from fluidization).
    PointStarted {
        /// Point index.
        point: usize,
    },
    /// A point's bed was prepared (or could not be).
    BedPrepared {
        /// Point index.
        point: usize,
        /// How.
        preparation: Preparation,
    },
    /// A point's jump ran and its log and frames are in its folder.
    Jumped {
        /// Point index.
        point: usize,
    },
    /// A point's analyses finished.
    Analysed {
        /// Point index.
        point: usize,
    },
    /// A point is done (jumped and analysed, or failed and recorded): its row.
    Done {
        /// The results row.
        row: ResultRow,
    },
    /// A point in progress when the previous session ended; it starts again from
    /// fluidization.
    Interrupted {
        /// Point index.
        point: usize,
        /// The last phase it had reached: `started`, `bed-prepared`, `jumped`, `analysed`.
        phase: String,
    },
    /// The campaign ended.
    Finished {
        /// `success` (every point done), `abort` (stopped by its failure policy).
        exit_status: String,
        /// Why, when not a success.
        reason: String,
    },
}

/// The journal file, open for appending.
pub struct Journal {
    file: File,
    path: PathBuf,
    next_seq: u64,
    /// Records read when it was opened.
    pub records: Vec<Record>,
    /// Bytes of a cut last line dropped when it was opened.
    pub dropped_partial_bytes: usize,
}

/// Read the records of `path` without changing it: the records, and the bytes of a cut
/// last line.
pub fn read(path: &Path) -> Result<(Vec<Record>, usize), String> {
    let bytes = std::fs::read(path)
        .map_err(|e| format!("cannot read the journal {}: {e}", path.display()))?;
    let end = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |k| k + 1);
    let text = std::str::from_utf8(&bytes[..end])
        .map_err(|e| format!("{}: not UTF-8 ({e})", path.display()))?;
    let mut records = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let r: Record = serde_json::from_str(line).map_err(|e| {
            format!(
                "{}:{}: a corrupt journal record ({e}); the campaign cannot be resumed from it",
                path.display(),
                k + 1
            )
        })?;
        records.push(r);
    }
    Ok((records, bytes.len() - end))
}

impl Journal {
    /// Create a new journal at `path` (refused if it exists).
    pub fn create(path: &Path) -> Result<Self, String> {
        let file = OpenOptions::new()
            .create_new(true)
            .append(true)
            .open(path)
            .map_err(|e| format!("cannot create the journal {}: {e}", path.display()))?;
        Ok(Self {
            file,
            path: path.to_path_buf(),
            next_seq: 0,
            records: Vec::new(),
            dropped_partial_bytes: 0,
        })
    }

    /// Open an existing journal for appending, dropping a cut last line.
    pub fn open(path: &Path) -> Result<Self, String> {
        let (records, dropped) = read(path)?;
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(|e| format!("cannot open the journal {}: {e}", path.display()))?;
        let len = file
            .seek(std::io::SeekFrom::End(0))
            .map_err(|e| format!("{}: {e}", path.display()))?;
        if dropped > 0 {
            file.set_len(len - dropped as u64)
                .and_then(|()| file.sync_data())
                .map_err(|e| format!("cannot cut the journal's partial line: {e}"))?;
        }
        file.seek(std::io::SeekFrom::End(0))
            .map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(Self {
            file,
            path: path.to_path_buf(),
            next_seq: records.last().map_or(0, |r| r.seq + 1),
            records,
            dropped_partial_bytes: dropped,
        })
    }

    /// Append `event`, flushed to the disk before this returns.
    pub fn append(&mut self, event: Event) -> Result<Record, String> {
        let rec = Record {
            seq: self.next_seq,
            time: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
            event,
        };
        let mut line = serde_json::to_string(&rec).map_err(|e| e.to_string())?;
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.sync_data())
            .map_err(|e| format!("cannot write the journal {}: {e}", self.path.display()))?;
        self.next_seq += 1;
        self.records.push(rec.clone());
        Ok(rec)
    }
}
