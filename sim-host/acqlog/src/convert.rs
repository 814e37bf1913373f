//! `sandjumper log convert` as a call: a binary log to the CSV form, or a CSV or binary log
//! to MCAP.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::binary::ConvertReport;
use super::check::{LogError, is_binary, load};
use super::mcap_file::McapReport;
use sandjumper_output::Progress;

/// What `log convert` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum LogForm {
    /// The CSV form (`sandjumper-acqlog 1`).
    Csv,
    /// MCAP (see [`super::mcap_file`]).
    Mcap,
}

/// `log convert`: what to read, what to write.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConvertRequest {
    /// The log to convert: binary for CSV, CSV or binary for MCAP.
    pub input: PathBuf,
    /// The file to write (not replaced if it exists, unless `force`).
    pub output: PathBuf,
    /// What to write; `None`: MCAP if `output` ends in `.mcap`, else CSV.
    pub to: Option<LogForm>,
    /// Convert even if sequence numbers show lost samples.
    pub allow_gaps: bool,
    /// Replace `output` if it exists.
    pub force: bool,
}

impl ConvertRequest {
    /// The form to write: `to`, else from the output's extension.
    pub fn form(&self) -> LogForm {
        self.to.unwrap_or(
            if self
                .output
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
            {
                LogForm::Mcap
            } else {
                LogForm::Csv
            },
        )
    }
}

/// What a conversion wrote.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "to", rename_all = "lowercase")]
pub enum ConvertOutcome {
    /// A binary log as CSV.
    Csv {
        /// The file written.
        output: PathBuf,
        /// What the conversion saw.
        report: ConvertReport,
    },
    /// A log as MCAP.
    Mcap {
        /// The file written.
        output: PathBuf,
        /// Samples in the log.
        samples: usize,
        /// Of which interpolated (gaps accepted).
        interpolated: u64,
        /// Messages and chunks written.
        report: McapReport,
        /// What the conversion of a binary input saw (`None` for CSV).
        conversion: Option<ConvertReport>,
    },
}

impl std::fmt::Display for ConvertOutcome {
    /// The lines `log convert` prints on stderr when it is done.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Csv { output, report } => writeln!(
                f,
                "wrote {} ({} samples from {} frames; {} rejected frames; {} samples lost by sequence number)",
                output.display(),
                report.samples,
                report.frames_ok,
                report.frames_rejected,
                report.samples_lost
            ),
            Self::Mcap {
                output,
                samples,
                interpolated,
                report,
                conversion,
            } => {
                let counts: Vec<String> = report
                    .messages
                    .iter()
                    .map(|(topic, n)| format!("{topic} {n}"))
                    .collect();
                writeln!(
                    f,
                    "wrote {} ({samples} samples, {interpolated} interpolated; {} chunks; messages: {})",
                    output.display(),
                    report.chunks,
                    counts.join(", ")
                )?;
                if let Some(c) = conversion {
                    writeln!(
                        f,
                        "from binary: {} frames, {} rejected, {} samples lost by sequence number",
                        c.frames_ok, c.frames_rejected, c.samples_lost
                    )?;
                }
                Ok(())
            }
        }
    }
}

/// An existing output is replaced only with `force`.
fn refuse_overwrite(r: &ConvertRequest) -> Result<(), LogError> {
    if r.output.exists() && !r.force {
        return Err(LogError::Exists {
            path: r.output.clone(),
        });
    }
    Ok(())
}

/// Write `out` through `write` into `out` with extension `tmp_extension`, then rename it into
/// place: a failed conversion leaves no half file.
fn write_then_rename<T>(
    out: &Path,
    tmp_extension: &str,
    write: impl FnOnce(&Path) -> Result<T, super::AcqLogError>,
) -> Result<T, LogError> {
    let tmp = out.with_extension(tmp_extension);
    write(&tmp)
        .and_then(|r| {
            std::fs::rename(&tmp, out).map_err(|e| super::AcqLogError::io(&e))?;
            Ok(r)
        })
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            LogError::Write {
                path: out.to_path_buf(),
                message: e.to_string(),
            }
        })
}

/// Convert `request.input` into `request.output`.
pub fn run(request: &ConvertRequest, progress: &dyn Progress) -> Result<ConvertOutcome, LogError> {
    let _ = progress;
    if request.form() == LogForm::Mcap {
        return to_mcap(request);
    }
    if !is_binary(&request.input)? {
        return Err(LogError::Bad {
            path: request.input.clone(),
            message: "not a binary log (no `SJACQBIN` header); a CSV log needs no conversion (check it with `sandjumper log check`)".into(),
        });
    }
    refuse_overwrite(request)?;
    let (log, report) = load(&request.input, request.allow_gaps)?;
    write_then_rename(&request.output, "csv.partial", |tmp| log.write_file(tmp))?;
    Ok(ConvertOutcome::Csv {
        output: request.output.clone(),
        report: report.unwrap_or_default(),
    })
}

fn to_mcap(request: &ConvertRequest) -> Result<ConvertOutcome, LogError> {
    refuse_overwrite(request)?;
    // The same reader and the same refusals as `log check` and `replay`.
    let (log, conversion) = load(&request.input, request.allow_gaps)?;
    let report = write_then_rename(&request.output, "mcap.partial", |tmp| {
        log.write_mcap_file(tmp, conversion.as_ref())
    })?;
    Ok(ConvertOutcome::Mcap {
        output: request.output.clone(),
        samples: log.rows.len(),
        interpolated: log.interpolated_samples(),
        report,
        conversion,
    })
}
