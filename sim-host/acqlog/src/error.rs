//! Why an acquisition log was refused: the line, the problem, what is allowed.

use std::fmt;

/// What kind of problem a log has (for callers and tests that branch on it; the
/// human-readable detail is in [`AcqLogError::message`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AcqLogErrorKind {
    /// Reading or writing the underlying file failed.
    Io,
    /// The file holds nothing (or only blank lines).
    Empty,
    /// A line is not valid UTF-8.
    NotUtf8,
    /// A line is longer than the reader's cap.
    LineTooLong,
    /// More samples than the reader's cap.
    TooManyRows,
    /// A `#` line that is not `# key: value`, or a duplicated key.
    MalformedMetadata,
    /// A required metadata key (`rate_hz`, `counts_per_m`) is absent.
    MissingMetadata,
    /// A metadata value that is not allowed (not a number, out of range, unknown word).
    BadMetadataValue,
    /// `format:` names a format or version this reader does not know.
    UnsupportedFormat,
    /// No header line before the samples (or the file ends after the metadata).
    MissingHeader,
    /// A header names a column the format does not have.
    UnknownColumn,
    /// A header names a column twice.
    DuplicateColumn,
    /// A required column (`t_s`, `encoder_counts`) is absent.
    MissingColumn,
    /// A row has more or fewer fields than the header.
    FieldCount,
    /// A field is not a number of the column's type.
    NotANumber,
    /// A field is NaN or infinite.
    NotFinite,
    /// A required field is empty.
    EmptyField,
    /// Time goes backwards.
    NonMonotonicTime,
    /// The same time twice.
    DuplicateTime,
    /// Samples are missing (time or tick skips); accepted only with `allow_gaps`.
    Gap,
    /// An interval is not close to a whole number of sampling periods.
    IrregularInterval,
    /// `rate_hz` disagrees with the time column.
    RateMismatch,
    /// The `tick` column disagrees with the time column, or does not increase.
    TickMismatch,
    /// The header is there but no sample rows follow.
    NoSamples,
    /// A value the writer was asked to write is not allowed (NaN, time going backwards...).
    BadRow,
    /// The binary form is malformed (bad magic, version, frame, CRC or sequence).
    Binary,
}

/// A refused log: where (1-based line number, when the problem has one) and what.
#[derive(Clone, Debug, PartialEq)]
pub struct AcqLogError {
    /// What kind of problem.
    pub kind: AcqLogErrorKind,
    /// 1-based line (CSV) or frame (binary) number, if the problem sits at one.
    pub line: Option<u64>,
    /// What was wrong and what is allowed.
    pub message: String,
}

impl AcqLogError {
    /// A problem at a given 1-based line.
    pub fn at(line: u64, kind: AcqLogErrorKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            line: Some(line),
            message: message.into(),
        }
    }

    /// A problem with the file as a whole.
    pub fn whole(kind: AcqLogErrorKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            line: None,
            message: message.into(),
        }
    }

    /// An I/O error on the whole log.
    pub fn io(err: &std::io::Error) -> Self {
        Self::whole(AcqLogErrorKind::Io, err.to_string())
    }
}

impl fmt::Display for AcqLogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "line {line}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

impl std::error::Error for AcqLogError {}
