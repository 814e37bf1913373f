//! Streaming writer: metadata, header, then one row per control tick.

use super::columns::{Column, ColumnSet, LogRow};
use super::error::{AcqLogError, AcqLogErrorKind};
use super::metadata::LogMetadata;
use std::fmt::Write as _;
use std::io::Write;

/// Writes a log row by row. Numbers are written in Rust's shortest round-trip form, so
/// writing then reading gives back exactly the same values.
///
/// The writer refuses rows the reader would refuse (non-finite values, time or tick not
/// increasing, a value for a column the log does not have): nothing is dropped silently.
/// Tick gaps (lost samples) are allowed and show in the `tick` column.
pub struct LogWriter<W: Write> {
    out: W,
    columns: ColumnSet,
    last: Option<(f64, Option<u64>)>,
    rows: u64,
    line: String,
}

impl<W: Write> LogWriter<W> {
    /// Writes the metadata block and the header line. `columns` must contain `t_s` and
    /// `encoder_counts` (use [`ColumnSet::sandjumper`] plus the optional ones you record).
    pub fn new(mut out: W, meta: &LogMetadata, columns: ColumnSet) -> Result<Self, AcqLogError> {
        meta.validate()?;
        let columns = columns.with(Column::TimeS).with(Column::EncoderCounts);
        let header: Vec<&str> = columns.iter().map(Column::name).collect();
        let text = format!("{}{}\n", meta.to_lines(), header.join(","));
        out.write_all(text.as_bytes())
            .map_err(|e| AcqLogError::io(&e))?;
        Ok(Self {
            out,
            columns,
            last: None,
            rows: 0,
            line: String::new(),
        })
    }

    /// Columns this log has.
    pub fn columns(&self) -> ColumnSet {
        self.columns
    }

    /// Rows written so far.
    pub fn rows_written(&self) -> u64 {
        self.rows
    }

    /// Appends one row.
    pub fn write_row(&mut self, row: &LogRow) -> Result<(), AcqLogError> {
        let index = self.rows;
        let bad = |msg: String| {
            AcqLogError::whole(AcqLogErrorKind::BadRow, format!("row {index}: {msg}"))
        };
        for column in Column::ALL {
            if row.has(column) && !self.columns.contains(column) {
                return Err(bad(format!(
                    "has a value for `{}` but the log was opened without that column",
                    column.name()
                )));
            }
        }
        if self.columns.contains(Column::Tick) && row.tick.is_none() {
            return Err(bad("has no tick but the log has a `tick` column".into()));
        }
        for (name, value) in [
            ("t_s", Some(row.t_s)),
            ("p_cmd_m", row.p_cmd_m),
            ("force_cmd_n", row.force_cmd_n),
            ("current_a", row.current_a),
            ("rod_height_m", row.rod_height_m),
        ] {
            if let Some(v) = value
                && !v.is_finite()
            {
                return Err(bad(format!("{name} = {v} is not a finite number")));
            }
        }
        if let Some((last_t, last_tick)) = self.last {
            if row.t_s <= last_t {
                return Err(bad(format!(
                    "t_s = {} does not increase (previous row {last_t})",
                    row.t_s
                )));
            }
            if let (Some(prev), Some(tick)) = (last_tick, row.tick)
                && tick <= prev
            {
                return Err(bad(format!(
                    "tick {tick} does not increase (previous row {prev})"
                )));
            }
        }
        self.line.clear();
        let mut first = true;
        for column in self.columns.iter() {
            if !first {
                self.line.push(',');
            }
            first = false;
            let _ = match column {
                Column::Tick => write_opt(&mut self.line, row.tick),
                Column::TimeS => write!(self.line, "{}", row.t_s),
                Column::EncoderCounts => write!(self.line, "{}", row.encoder_counts),
                Column::PCmdM => write_opt(&mut self.line, row.p_cmd_m),
                Column::ForceCmdN => write_opt(&mut self.line, row.force_cmd_n),
                Column::CurrentA => write_opt(&mut self.line, row.current_a),
                Column::CameraFrame => write_opt(&mut self.line, row.camera_frame),
                Column::Flags => write_opt(&mut self.line, row.flags),
                Column::RodHeightM => write_opt(&mut self.line, row.rod_height_m),
            };
        }
        self.line.push('\n');
        self.out
            .write_all(self.line.as_bytes())
            .map_err(|e| AcqLogError::io(&e))?;
        self.last = Some((row.t_s, row.tick));
        self.rows += 1;
        Ok(())
    }

    /// Flushes and returns the underlying writer.
    pub fn finish(mut self) -> Result<W, AcqLogError> {
        self.out.flush().map_err(|e| AcqLogError::io(&e))?;
        Ok(self.out)
    }
}

fn write_opt<T: std::fmt::Display>(s: &mut String, value: Option<T>) -> std::fmt::Result {
    match value {
        Some(v) => write!(s, "{v}"),
        None => Ok(()),
    }
}
