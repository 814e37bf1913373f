//! `sandjumper log check FILE` and `sandjumper log convert IN OUT`.

use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use serde::Serialize;

use super::binary::{ConvertReport, MAGIC, convert_binary};
use super::reader::ReadOptions;
use super::summary::LogSummary;
use super::{AcqLog, read_log};
use sandjumper_output::CliError;

/// `sandjumper log`.
#[derive(Debug, Clone, Args)]
pub struct LogArgs {
    /// What to do with the log.
    #[command(subcommand)]
    pub action: LogAction,
}

/// `sandjumper log` actions.
#[derive(Debug, Clone, Subcommand)]
pub enum LogAction {
    /// Validate a log (CSV or binary) and summarise it: duration, rate, gaps, faults, camera
    /// frames, dropped samples. Exit status 2 if it is not a valid log.
    Check(CheckArgs),
    /// Convert a binary log (the rig's frames as received) to the CSV form, losslessly; or a
    /// CSV or binary log to MCAP (OUT ending in `.mcap`, or `--to mcap`) for Foxglove,
    /// Lichtblick and PlotJuggler.
    Convert(ConvertArgs),
}

/// `sandjumper log check`.
#[derive(Debug, Clone, Args)]
pub struct CheckArgs {
    /// The log.
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Accept missing samples (interpolated, and counted in the summary).
    #[arg(long)]
    pub allow_gaps: bool,
    /// Print one JSON object instead of the text summary.
    #[arg(long)]
    pub json: bool,
}

/// `sandjumper log convert`.
#[derive(Debug, Clone, Args)]
pub struct ConvertArgs {
    /// The log to convert: binary for `--to csv`, CSV or binary for `--to mcap`.
    #[arg(value_name = "IN")]
    pub input: PathBuf,
    /// The file to write (not overwritten if it exists, unless --force).
    #[arg(value_name = "OUT")]
    pub output: PathBuf,
    /// What to write: `csv` (the default, unless OUT ends in `.mcap`) or `mcap` (one channel
    /// per quantity group, JSON messages with JSON schemas, chunked and indexed).
    #[arg(long, value_enum, value_name = "FORM")]
    pub to: Option<ConvertTo>,
    /// Convert even if sequence numbers show lost samples (the CSV's tick column shows the
    /// gaps and `dropped_samples` counts them).
    #[arg(long)]
    pub allow_gaps: bool,
    /// Replace OUT if it exists.
    #[arg(long)]
    pub force: bool,
}

/// What `log convert` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ConvertTo {
    /// The CSV form (`sandjumper-acqlog 1`).
    Csv,
    /// MCAP (see [`super::mcap_file`]).
    Mcap,
}

/// Run `log`.
pub fn run(a: &LogArgs) -> Result<(), CliError> {
    match &a.action {
        LogAction::Check(c) => check(c),
        LogAction::Convert(c) => convert(c),
    }
}

/// JSON of `log check --json`.
#[derive(Serialize)]
struct CheckReport<'a> {
    file: String,
    form: &'static str,
    #[serde(flatten)]
    summary: &'a LogSummary,
    conversion: Option<&'a ConvertReport>,
}

fn bad(path: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::input(format!("log `{}`: {e}", path.display()))
}

fn is_binary(path: &Path) -> Result<bool, CliError> {
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

fn load(path: &Path, allow_gaps: bool) -> Result<(AcqLog, Option<ConvertReport>), CliError> {
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

/// Reads and checks a log (CSV or binary) as `log check` does: the log and the JSON object
/// `log check --json` prints. Errors are the CLI's.
pub fn load_checked(path: &Path, allow_gaps: bool) -> Result<(AcqLog, String), CliError> {
    let (log, conversion) = load(path, allow_gaps)?;
    let json = check_json(path, &log, conversion.as_ref())?;
    Ok((log, json))
}

fn check_json(
    path: &Path,
    log: &AcqLog,
    conversion: Option<&ConvertReport>,
) -> Result<String, CliError> {
    let summary = log.summary();
    let report = CheckReport {
        file: path.display().to_string(),
        form: if conversion.is_some() {
            "binary"
        } else {
            "csv"
        },
        summary: &summary,
        conversion,
    };
    serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary as JSON: {e}")))
}

fn check(a: &CheckArgs) -> Result<(), CliError> {
    let (log, conversion) = load(&a.file, a.allow_gaps)?;
    let summary = log.summary();
    if a.json {
        println!("{}", check_json(&a.file, &log, conversion.as_ref())?);
        return Ok(());
    }
    println!(
        "{}: valid {} log",
        a.file.display(),
        if conversion.is_some() {
            "binary"
        } else {
            "CSV"
        }
    );
    print!("{summary}");
    if let Some(c) = &conversion {
        println!(
            "frames:             {} decoded ({} sample batches), {} rejected, {} other messages",
            c.frames_ok, c.sample_batches, c.frames_rejected, c.other_messages
        );
        println!("samples lost (seq): {}", c.samples_lost);
        for (code, name, tick) in &c.faults {
            println!("fault reported:     {code} {name} at tick {tick}");
        }
    }
    Ok(())
}

/// An existing OUT is replaced only with `--force`.
fn refuse_overwrite(a: &ConvertArgs) -> Result<(), CliError> {
    if a.output.exists() && !a.force {
        return Err(CliError::input(format!(
            "`{}` exists: choose another name or pass --force",
            a.output.display()
        )));
    }
    Ok(())
}

/// Write `out` through `write` into `out` with extension `tmp_extension`, then rename it into
/// place: a failed conversion leaves no half file.
fn write_then_rename<T>(
    out: &Path,
    tmp_extension: &str,
    write: impl FnOnce(&Path) -> Result<T, super::AcqLogError>,
) -> Result<T, CliError> {
    let tmp = out.with_extension(tmp_extension);
    write(&tmp)
        .and_then(|r| {
            std::fs::rename(&tmp, out).map_err(|e| super::AcqLogError::io(&e))?;
            Ok(r)
        })
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            CliError::input(format!("cannot write `{}`: {e}", out.display()))
        })
}

fn convert(a: &ConvertArgs) -> Result<(), CliError> {
    let to = a.to.unwrap_or(
        if a.output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
        {
            ConvertTo::Mcap
        } else {
            ConvertTo::Csv
        },
    );
    if to == ConvertTo::Mcap {
        return convert_to_mcap(a);
    }
    if !is_binary(&a.input)? {
        return Err(bad(
            &a.input,
            "not a binary log (no `SJACQBIN` header); a CSV log needs no conversion (check it with `sandjumper log check`)",
        ));
    }
    refuse_overwrite(a)?;
    let (log, report) = load(&a.input, a.allow_gaps)?;
    let report = report.unwrap_or_default();
    write_then_rename(&a.output, "csv.partial", |tmp| log.write_file(tmp))?;
    eprintln!(
        "wrote {} ({} samples from {} frames; {} rejected frames; {} samples lost by sequence number)",
        a.output.display(),
        report.samples,
        report.frames_ok,
        report.frames_rejected,
        report.samples_lost
    );
    Ok(())
}

fn convert_to_mcap(a: &ConvertArgs) -> Result<(), CliError> {
    refuse_overwrite(a)?;
    // The same reader and the same refusals as `log check` and `replay`.
    let (log, conversion) = load(&a.input, a.allow_gaps)?;
    let report = write_then_rename(&a.output, "mcap.partial", |tmp| {
        log.write_mcap_file(tmp, conversion.as_ref())
    })?;
    let counts: Vec<String> = report
        .messages
        .iter()
        .map(|(topic, n)| format!("{topic} {n}"))
        .collect();
    eprintln!(
        "wrote {} ({} samples, {} interpolated; {} chunks; messages: {})",
        a.output.display(),
        log.rows.len(),
        log.interpolated_samples(),
        report.chunks,
        counts.join(", ")
    );
    if let Some(c) = &conversion {
        eprintln!(
            "from binary: {} frames, {} rejected, {} samples lost by sequence number",
            c.frames_ok, c.frames_rejected, c.samples_lost
        );
    }
    Ok(())
}
