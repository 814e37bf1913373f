//! Strict, streaming reader: one pass, bounded memory per line, a capped number of rows.

use super::columns::{Column, ColumnSet, LogRow};
use super::error::{AcqLogError, AcqLogErrorKind as Kind};
use super::metadata::{MetadataBuilder, truncate};
use super::{AcqLog, Gap};
use std::io::{BufRead, Read};

/// How strict the reader is and how much it accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadOptions {
    /// Accept missing samples and fill them by linear interpolation (reported in
    /// [`AcqLog::gaps`]). Off by default: a gap is an error.
    pub allow_gaps: bool,
    /// Most samples accepted, interpolated ones included (default 2,000,000: 200 s at 10 kHz).
    pub max_rows: usize,
    /// Longest line accepted, bytes (default 4096).
    pub max_line_bytes: usize,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            allow_gaps: false,
            max_rows: 2_000_000,
            max_line_bytes: 4096,
        }
    }
}

/// An interval may differ from a whole number of sampling periods by at most this fraction
/// of a period (timestamp jitter).
pub const INTERVAL_TOLERANCE: f64 = 0.25;
/// The mean sampling period from the time column may differ from `1 / rate_hz` by at most
/// this fraction.
pub const RATE_TOLERANCE: f64 = 0.01;

/// Where a header column's values go.
#[derive(Clone, Copy)]
enum Slot {
    Known(Column),
    Ignored,
}

/// Reads and checks a whole log. Every refusal names the line and the problem.
pub fn read_log<R: BufRead>(mut input: R, opts: &ReadOptions) -> Result<AcqLog, AcqLogError> {
    let mut buf = Vec::new();
    let mut line_no: u64 = 0;
    let mut meta = MetadataBuilder::default();
    let mut header: Option<(Vec<Slot>, ColumnSet, u64)> = None;
    let mut log: Option<AcqLog> = None;
    let mut saw_anything = false;
    loop {
        buf.clear();
        let limit = opts.max_line_bytes as u64 + 2;
        let n = Read::take(&mut input, limit)
            .read_until(b'\n', &mut buf)
            .map_err(|e| AcqLogError::io(&e))?;
        if n == 0 {
            break;
        }
        line_no += 1;
        if buf.last() == Some(&b'\n') {
            buf.pop();
        } else if n as u64 == limit {
            return Err(AcqLogError::at(
                line_no,
                Kind::LineTooLong,
                format!("line longer than {} bytes", opts.max_line_bytes),
            ));
        }
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
        let text = std::str::from_utf8(&buf).map_err(|e| {
            AcqLogError::at(
                line_no,
                Kind::NotUtf8,
                format!("not valid UTF-8 text (byte {})", e.valid_up_to() + 1),
            )
        })?;
        let text = if line_no == 1 {
            text.strip_prefix('\u{feff}').unwrap_or(text)
        } else {
            text
        };
        if text.trim().is_empty() {
            continue;
        }
        saw_anything = true;
        if text.starts_with('#') {
            if header.is_some() {
                return Err(AcqLogError::at(
                    line_no,
                    Kind::MalformedMetadata,
                    "`#` line after the header: metadata goes above the header line",
                ));
            }
            meta.push_line(line_no, text)?;
            continue;
        }
        match (&header, &mut log) {
            (None, _) => {
                let (slots, set) = parse_header(line_no, text)?;
                let metadata = std::mem::take(&mut meta).finish(line_no)?;
                log = Some(AcqLog {
                    meta: metadata,
                    columns: set,
                    rows: Vec::new(),
                    gaps: Vec::new(),
                });
                header = Some((slots, set, line_no));
            }
            (Some((slots, _, _)), Some(log)) => {
                let row = parse_row(line_no, text, slots)?;
                push_row(log, row, line_no, opts)?;
            }
            (Some(_), None) => unreachable!("header and log are set together"),
        }
    }
    if !saw_anything {
        return Err(AcqLogError::whole(
            Kind::Empty,
            "empty file: expected `# rate_hz: ...` and `# counts_per_m: ...` lines, a header (at least `t_s,encoder_counts`) and one row per sample",
        ));
    }
    let Some(log) = log else {
        return Err(AcqLogError::at(
            line_no,
            Kind::MissingHeader,
            "file ends before the header line (e.g. `tick,t_s,encoder_counts`)",
        ));
    };
    if log.rows.is_empty() {
        return Err(AcqLogError::at(
            line_no,
            Kind::NoSamples,
            "no sample rows after the header",
        ));
    }
    check_rate(&log)?;
    Ok(log)
}

fn parse_header(line_no: u64, text: &str) -> Result<(Vec<Slot>, ColumnSet), AcqLogError> {
    let mut slots = Vec::new();
    let mut set = ColumnSet::default();
    for name in text.split(',').map(str::trim) {
        if let Some(column) = Column::from_name(name) {
            if set.contains(column) {
                return Err(AcqLogError::at(
                    line_no,
                    Kind::DuplicateColumn,
                    format!("column `{name}` appears twice in the header"),
                ));
            }
            set = set.with(column);
            slots.push(Slot::Known(column));
        } else if name.starts_with("x_") {
            slots.push(Slot::Ignored);
        } else {
            let allowed: Vec<&str> = Column::ALL.iter().map(|c| c.name()).collect();
            return Err(AcqLogError::at(
                line_no,
                Kind::UnknownColumn,
                format!(
                    "unknown column `{}` in the header; allowed: {} (extra columns must start with `x_`)",
                    truncate(name),
                    allowed.join(", ")
                ),
            ));
        }
    }
    for column in [Column::TimeS, Column::EncoderCounts] {
        if !set.contains(column) {
            return Err(AcqLogError::at(
                line_no,
                Kind::MissingColumn,
                format!(
                    "required column `{}` missing from the header `{}` (required: t_s, encoder_counts)",
                    column.name(),
                    truncate(text)
                ),
            ));
        }
    }
    Ok((slots, set))
}

fn parse_row(line_no: u64, text: &str, slots: &[Slot]) -> Result<LogRow, AcqLogError> {
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    if fields.len() != slots.len() {
        return Err(AcqLogError::at(
            line_no,
            Kind::FieldCount,
            format!(
                "{} fields but the header has {} columns",
                fields.len(),
                slots.len()
            ),
        ));
    }
    let mut row = LogRow::default();
    for (field, slot) in fields.iter().zip(slots) {
        let Slot::Known(column) = *slot else {
            continue;
        };
        if field.is_empty() {
            if column.required() || column == Column::Tick {
                return Err(AcqLogError::at(
                    line_no,
                    Kind::EmptyField,
                    format!(
                        "column `{}` is empty; it needs a value in every row",
                        column.name()
                    ),
                ));
            }
            continue;
        }
        let name = column.name();
        match column {
            Column::Tick => row.tick = Some(parse_int(line_no, name, field)?),
            Column::TimeS => row.t_s = parse_real(line_no, name, field)?,
            Column::EncoderCounts => row.encoder_counts = parse_int(line_no, name, field)?,
            Column::PCmdM => row.p_cmd_m = Some(parse_real(line_no, name, field)?),
            Column::ForceCmdN => row.force_cmd_n = Some(parse_real(line_no, name, field)?),
            Column::CurrentA => row.current_a = Some(parse_real(line_no, name, field)?),
            Column::CameraFrame => row.camera_frame = Some(parse_int(line_no, name, field)?),
            Column::Flags => row.flags = Some(parse_flags(line_no, field)?),
            Column::RodHeightM => row.rod_height_m = Some(parse_real(line_no, name, field)?),
        }
    }
    Ok(row)
}

fn parse_real(line_no: u64, name: &str, field: &str) -> Result<f64, AcqLogError> {
    match field.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(AcqLogError::at(
            line_no,
            Kind::NotFinite,
            format!("column `{name}` is {v}: values must be finite numbers"),
        )),
        Err(_) => Err(AcqLogError::at(
            line_no,
            Kind::NotANumber,
            format!("column `{name}`: `{}` is not a number", truncate(field)),
        )),
    }
}

fn parse_int<T: std::str::FromStr>(
    line_no: u64,
    name: &str,
    field: &str,
) -> Result<T, AcqLogError> {
    field.parse::<T>().map_err(|_| {
        let what = if field.parse::<f64>().is_ok() {
            "is not a whole number in range"
        } else {
            "is not a number"
        };
        AcqLogError::at(
            line_no,
            Kind::NotANumber,
            format!("column `{name}`: `{}` {what}", truncate(field)),
        )
    })
}

fn parse_flags(line_no: u64, field: &str) -> Result<u32, AcqLogError> {
    let parsed = match field
        .strip_prefix("0x")
        .or_else(|| field.strip_prefix("0X"))
    {
        Some(hex) => u32::from_str_radix(hex, 16).ok(),
        None => field.parse::<u32>().ok(),
    };
    parsed.ok_or_else(|| {
        AcqLogError::at(
            line_no,
            Kind::NotANumber,
            format!(
                "column `flags`: `{}` is not a 32-bit unsigned number (decimal or 0x hex)",
                truncate(field)
            ),
        )
    })
}

/// Checks the interval from the previous sample and appends (filling gaps if allowed).
fn push_row(
    log: &mut AcqLog,
    row: LogRow,
    line_no: u64,
    opts: &ReadOptions,
) -> Result<(), AcqLogError> {
    let period = log.meta.period_s();
    let too_many = || {
        AcqLogError::at(
            line_no,
            Kind::TooManyRows,
            format!(
                "more than {} samples (the reader's cap; {:.0} s at rate_hz {}): split the log",
                opts.max_rows,
                opts.max_rows as f64 * period,
                log.meta.rate_hz
            ),
        )
    };
    let Some(prev) = log.rows.last().copied() else {
        if opts.max_rows == 0 {
            return Err(too_many());
        }
        log.rows.push(row);
        return Ok(());
    };
    let dt = row.t_s - prev.t_s;
    if dt == 0.0 {
        return Err(AcqLogError::at(
            line_no,
            Kind::DuplicateTime,
            format!("t_s = {} repeats the previous row's time", row.t_s),
        ));
    }
    if dt < 0.0 {
        return Err(AcqLogError::at(
            line_no,
            Kind::NonMonotonicTime,
            format!(
                "t_s = {} is earlier than the previous row's {}: time must increase",
                row.t_s, prev.t_s
            ),
        ));
    }
    let periods = dt / period;
    let whole = periods.round();
    if whole < 1.0 {
        return Err(AcqLogError::at(
            line_no,
            Kind::RateMismatch,
            format!(
                "interval {dt:.6e} s from the previous row is less than half the period 1/rate_hz = {period:.6e} s: rate_hz = {} disagrees with the time column (which suggests about {:.6} Hz)",
                log.meta.rate_hz,
                1.0 / dt
            ),
        ));
    }
    if (periods - whole).abs() > INTERVAL_TOLERANCE {
        return Err(AcqLogError::at(
            line_no,
            Kind::IrregularInterval,
            format!(
                "interval {dt:.6e} s from the previous row is {periods:.3} sampling periods (1/rate_hz = {period:.6e} s); intervals must be within {INTERVAL_TOLERANCE} of a whole number of periods"
            ),
        ));
    }
    let steps = whole as u64;
    if let Some(tick) = row.tick {
        let prev_tick = prev.tick.unwrap_or(0);
        if tick <= prev_tick || tick - prev_tick != steps {
            return Err(AcqLogError::at(
                line_no,
                Kind::TickMismatch,
                format!(
                    "tick {tick} after tick {prev_tick} does not match t_s, which advanced {steps} period(s)"
                ),
            ));
        }
    }
    if steps > 1 {
        let missing = steps - 1;
        if !opts.allow_gaps {
            return Err(AcqLogError::at(
                line_no,
                Kind::Gap,
                format!(
                    "gap: {missing} sample(s) missing between t_s = {} and t_s = {}; pass --allow-gaps to accept it (the samples are then interpolated)",
                    prev.t_s, row.t_s
                ),
            ));
        }
        if (log.rows.len() as u64).saturating_add(steps) > opts.max_rows as u64 {
            return Err(too_many());
        }
        let span = (row.encoder_counts as f64) - (prev.encoder_counts as f64);
        for j in 1..steps {
            let frac = j as f64 / steps as f64;
            log.rows.push(LogRow {
                tick: prev.tick.map(|t| t + j),
                t_s: prev.t_s + dt * frac,
                encoder_counts: (prev.encoder_counts as f64 + span * frac).round() as i64,
                ..LogRow::default()
            });
        }
        log.gaps.push(Gap {
            line: line_no,
            after_t_s: prev.t_s,
            missing_samples: missing,
        });
    }
    if log.rows.len() >= opts.max_rows {
        return Err(too_many());
    }
    log.rows.push(row);
    Ok(())
}

/// Compares `rate_hz` with the least-squares sampling period of the time column.
fn check_rate(log: &AcqLog) -> Result<(), AcqLogError> {
    let Some(measured) = log.measured_period_s() else {
        return Ok(());
    };
    let nominal = log.meta.period_s();
    if ((measured - nominal) / nominal).abs() > RATE_TOLERANCE {
        return Err(AcqLogError::whole(
            Kind::RateMismatch,
            format!(
                "rate_hz = {} disagrees with the time column, whose mean rate is {:.6} Hz (allowed difference {} %)",
                log.meta.rate_hz,
                1.0 / measured,
                RATE_TOLERANCE * 100.0
            ),
        ));
    }
    Ok(())
}
