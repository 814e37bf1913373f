//! Acquisition logs: the encoder record of a jump, as the rig, `sandjumper hil --out` and
//! third-party acquisitions write it, and as `sandjumper replay` / `sandjumper log` read it.
//!
//! # The CSV form (format `sandjumper-acqlog 1`)
//!
//! ```text
//! # format: sandjumper-acqlog 1
//! # rate_hz: 10000
//! # counts_per_m: 1000000
//! # encoder_sign: +1
//! # position_offset_m: 0
//! # firmware: sandjumper-firmware 0.1.0
//! # jump_kind: single
//! # jump_amplitude_m: 0.01875
//! # jump_freq_hz: 10
//! # phi: 0.57
//! # dropped_samples: 0
//! tick,t_s,encoder_counts,p_cmd_m,force_cmd_n,camera_frame,flags
//! 0,0,-18750,-0.01875,13.1,0,0
//! 1,0.0001,-18750,-0.018749,13.2,,0
//! ```
//!
//! - Metadata lines come first, one `# key: value` each (keys: lowercase, digits, `_`;
//!   each at most once). `##` lines and a bare `#` are free comments. Required:
//!   `rate_hz` (samples per second) and `counts_per_m`. Optional: `format` (if present it
//!   must be `sandjumper-acqlog 1`), `encoder_sign` (`+1` default: counts increase when the
//!   motor moves up relative to the rod; `-1` otherwise), `position_offset_m` (`p` at count
//!   0, default 0), `firmware`, `source`, `jump_kind`/`jump_amplitude_m`/`jump_freq_hz`/
//!   `jump_tau_s`, `phi`, `dropped_samples` (default 0), `measured_jump_height_m`. Other keys
//!   are kept verbatim ([`LogMetadata::extra`]).
//! - Then one header line, comma-separated. Required columns `t_s` (s) and `encoder_counts`
//!   (integer); optional `tick` (integer; sandjumper always writes it), `p_cmd_m`,
//!   `force_cmd_n`, `current_a`, `camera_frame` (integer, empty when no frame), `flags`
//!   (decimal or `0x` hex), `rod_height_m` (camera-measured rod height above rest, empty when
//!   not measured). Extra columns must start with `x_` (ignored); any other name is an error,
//!   so a misspelt column is caught. Column order is free.
//! - Then one row per control tick. Time strictly increases; every interval must be within
//!   [`reader::INTERVAL_TOLERANCE`] of a whole number of periods `1/rate_hz`, and the mean
//!   rate within [`reader::RATE_TOLERANCE`] of `rate_hz`. An interval of more than one period
//!   is a gap (missing samples): refused unless [`ReadOptions::allow_gaps`], which fills it by
//!   linear interpolation and records it in [`AcqLog::gaps`]. With a `tick` column, ticks must
//!   advance by exactly the number of periods.
//!
//! Position of the motor relative to the rod: `p = encoder_sign * encoder_counts /
//! counts_per_m + position_offset_m` (docs/model.md `p = x_m - x_r`).

pub mod binary;
pub mod check;
pub mod columns;
pub mod convert;
pub mod error;
mod mcap_chunk_check;
pub mod mcap_file;
pub mod metadata;
pub mod reader;
pub mod summary;
pub mod writer;

pub use binary::{BinaryLogWriter, ConvertReport, SampleLogBuilder, convert_binary};
pub use check::{CheckOutcome, CheckRequest, LogError};
pub use columns::{Column, ColumnSet, LogRow};
pub use convert::{ConvertOutcome, ConvertRequest, LogForm};
pub use error::{AcqLogError, AcqLogErrorKind};
pub use mcap_file::{
    McapCompression, McapReport, ReadBack, read_messages, write_mcap, write_mcap_compressed,
};
pub use metadata::{JumpConfig, LogMetadata};
pub use reader::{ReadOptions, read_log};
pub use summary::LogSummary;
pub use writer::LogWriter;

use std::io::{BufReader, BufWriter};
use std::path::Path;

/// Missing samples that were filled by interpolation (only with `allow_gaps`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gap {
    /// Line of the first sample after the gap.
    pub line: u64,
    /// Time of the last sample before the gap, s.
    pub after_t_s: f64,
    /// How many samples were missing (and interpolated).
    pub missing_samples: u64,
}

/// A whole log in memory: metadata, which columns it has, and its rows.
#[derive(Clone, Debug, PartialEq)]
pub struct AcqLog {
    /// The `# key: value` lines.
    pub meta: LogMetadata,
    /// Which columns the log has.
    pub columns: ColumnSet,
    /// One row per sample, time increasing (interpolated rows included when gaps were
    /// allowed; their optional values are `None`).
    pub rows: Vec<LogRow>,
    /// Gaps filled by the reader (empty for a log written here or read without gaps).
    pub gaps: Vec<Gap>,
}

impl AcqLog {
    /// An empty log with sandjumper's standard columns plus `extra`, ready for rows.
    pub fn new(meta: LogMetadata, extra: &[Column]) -> Self {
        let columns = extra
            .iter()
            .fold(ColumnSet::sandjumper(), |set, c| set.with(*c));
        Self {
            meta,
            columns,
            rows: Vec::new(),
            gaps: Vec::new(),
        }
    }

    /// Reads and checks a log file.
    pub fn read_file(path: &Path, opts: &ReadOptions) -> Result<Self, AcqLogError> {
        let file = std::fs::File::open(path).map_err(|e| AcqLogError::io(&e))?;
        read_log(BufReader::new(file), opts)
    }

    /// Writes the log as CSV (metadata, header, rows) with [`LogWriter`]. Rows interpolated
    /// into gaps are written like any other row (check [`AcqLog::gaps`] first if that matters).
    pub fn write_csv<W: std::io::Write>(&self, out: W) -> Result<W, AcqLogError> {
        let mut writer = LogWriter::new(out, &self.meta, self.columns)?;
        for row in &self.rows {
            writer.write_row(row)?;
        }
        writer.finish()
    }

    /// Writes the log to a file.
    pub fn write_file(&self, path: &Path) -> Result<(), AcqLogError> {
        let file = std::fs::File::create(path).map_err(|e| AcqLogError::io(&e))?;
        self.write_csv(BufWriter::new(file)).map(drop)
    }

    /// Motor position relative to the rod at every sample, m.
    pub fn positions_m(&self) -> Vec<f64> {
        self.rows
            .iter()
            .map(|r| self.meta.position_m(r.encoder_counts))
            .collect()
    }

    /// Time from the first to the last sample, s.
    pub fn duration_s(&self) -> f64 {
        match (self.rows.first(), self.rows.last()) {
            (Some(a), Some(b)) => b.t_s - a.t_s,
            _ => 0.0,
        }
    }

    /// Samples that were interpolated into gaps.
    pub fn interpolated_samples(&self) -> u64 {
        self.gaps.iter().map(|g| g.missing_samples).sum()
    }

    /// Least-squares slope of `t_s` against sample index: the sampling period the time column
    /// actually shows, s. `None` with fewer than two samples.
    pub fn measured_period_s(&self) -> Option<f64> {
        let n = self.rows.len();
        if n < 2 {
            return None;
        }
        let nf = n as f64;
        let mean_i = (nf - 1.0) / 2.0;
        let t0 = self.rows[0].t_s;
        let mean_t = self.rows.iter().map(|r| r.t_s - t0).sum::<f64>() / nf;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for (i, r) in self.rows.iter().enumerate() {
            let di = i as f64 - mean_i;
            sxy += di * (r.t_s - t0 - mean_t);
            sxx += di * di;
        }
        Some(sxy / sxx)
    }

    /// Duration, rate, gaps, faults, frames: what `sandjumper log check` prints.
    pub fn summary(&self) -> LogSummary {
        LogSummary::of(self)
    }
}
