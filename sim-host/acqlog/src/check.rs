//! `sandjumper log check` as a call: read a log (CSV or binary), check it, summarise it.

use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::binary::{ConvertReport, MAGIC, convert_binary};
use super::reader::ReadOptions;
use super::summary::LogSummary;
use super::{AcqLog, read_log};
use sandjumper_output::{Blame, Blamed, Progress};

/// What `log check` and `log convert` return when they fail.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LogError {
    /// The log cannot be read or is not a valid log.
    #[error("log `{}`: {message}", path.display())]
    Bad {
        /// The log.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// The file to write exists and the request does not replace it.
    #[error("`{}` exists: choose another name or pass --force", path.display())]
    Exists {
        /// The file.
        path: PathBuf,
    },
    /// The converted log could not be written (nothing is left at its path).
    #[error("cannot write `{}`: {message}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The summary could not be encoded as JSON.
    #[error("cannot encode the summary as JSON: {0}")]
    Encode(String),
}

impl Blamed for LogError {
    fn blame(&self) -> Blame {
        match self {
            Self::Encode(_) => Blame::Internal,
            _ => Blame::Input,
        }
    }
}

fn bad(path: &Path, e: impl std::fmt::Display) -> LogError {
    LogError::Bad {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// `log check`: which log, and whether missing samples are accepted.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckRequest {
    /// The log (CSV, or binary starting with `SJACQBIN`).
    pub file: PathBuf,
    /// Accept missing samples (interpolated, and counted in the summary).
    pub allow_gaps: bool,
}

/// A valid log and its summary: what `log check --json` prints (`file`, `form`, the
/// summary's keys, `conversion`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CheckOutcome {
    /// The log's path as given.
    pub file: String,
    /// `csv` or `binary`.
    pub form: &'static str,
    /// Duration, rate, gaps, faults, frames, position range.
    #[serde(flatten)]
    pub summary: LogSummary,
    /// What the conversion of a binary log saw (`None` for CSV).
    pub conversion: Option<ConvertReport>,
    /// The log itself.
    #[serde(skip)]
    pub log: AcqLog,
}

impl std::fmt::Display for CheckOutcome {
    /// The text `log check` prints without `--json`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let form = if self.conversion.is_some() {
            "binary"
        } else {
            "CSV"
        };
        writeln!(f, "{}: valid {form} log", self.file)?;
        write!(f, "{}", self.summary)?;
        if let Some(c) = &self.conversion {
            writeln!(
                f,
                "frames:             {} decoded ({} sample batches), {} rejected, {} other messages",
                c.frames_ok, c.sample_batches, c.frames_rejected, c.other_messages
            )?;
            writeln!(f, "samples lost (seq): {}", c.samples_lost)?;
            for (code, name, tick) in &c.faults {
                writeln!(f, "fault reported:     {code} {name} at tick {tick}")?;
            }
        }
        Ok(())
    }
}

impl CheckOutcome {
    /// The JSON `log check --json` prints (pretty, without a final newline).
    pub fn json(&self) -> Result<String, LogError> {
        serde_json::to_string_pretty(self).map_err(|e| LogError::Encode(e.to_string()))
    }
}

/// Whether `path` starts with the binary log's magic bytes.
pub fn is_binary(path: &Path) -> Result<bool, LogError> {
    let mut head = [0u8; 8];
    let mut file = std::fs::File::open(path).map_err(|e| bad(path, e))?;
    let mut got = 0;
    while got < head.len() {
        match file.read(&mut head[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) => return Err(bad(path, e)),
        }
    }
    Ok(got == head.len() && &head == MAGIC)
}

/// Read a log, CSV or binary (the binary's conversion report with it).
pub fn load(path: &Path, allow_gaps: bool) -> Result<(AcqLog, Option<ConvertReport>), LogError> {
    let opts = ReadOptions {
        allow_gaps,
        ..ReadOptions::default()
    };
    let file = std::fs::File::open(path).map_err(|e| bad(path, e))?;
    if is_binary(path)? {
        let (log, report) = convert_binary(BufReader::new(file), allow_gaps, opts.max_rows)
            .map_err(|e| bad(path, e))?;
        Ok((log, Some(report)))
    } else {
        let log = read_log(BufReader::new(file), &opts).map_err(|e| bad(path, e))?;
        Ok((log, None))
    }
}

/// Read and check the log `request.file`; its summary.
pub fn run(request: &CheckRequest, progress: &dyn Progress) -> Result<CheckOutcome, LogError> {
    let _ = progress;
    let (log, conversion) = load(&request.file, request.allow_gaps)?;
    Ok(CheckOutcome {
        file: request.file.display().to_string(),
        form: if conversion.is_some() {
            "binary"
        } else {
            "csv"
        },
        summary: log.summary(),
        conversion,
        log,
    })
}
