//! `sandjumper log check FILE` and `sandjumper log convert IN OUT`.

use std::path::PathBuf;

use clap::{Args, Subcommand};

use super::{CheckRequest, ConvertRequest, LogForm};
use crate::command::CliError;
use sandjumper_output::Silent;

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
    pub to: Option<LogForm>,
    /// Convert even if sequence numbers show lost samples (the CSV's tick column shows the
    /// gaps and `dropped_samples` counts them).
    #[arg(long)]
    pub allow_gaps: bool,
    /// Replace OUT if it exists.
    #[arg(long)]
    pub force: bool,
}

/// Run `log`.
pub fn run(a: &LogArgs) -> Result<(), CliError> {
    match &a.action {
        LogAction::Check(c) => check(c),
        LogAction::Convert(c) => convert(c),
    }
}

fn check(a: &CheckArgs) -> Result<(), CliError> {
    let request = CheckRequest {
        file: a.file.clone(),
        allow_gaps: a.allow_gaps,
    };
    let outcome = super::check::run(&request, &Silent)?;
    crate::command::print_outcome(a.json, &outcome, || outcome.json())
}

impl ConvertArgs {
    /// The library's request for these arguments.
    pub fn request(&self) -> ConvertRequest {
        ConvertRequest {
            input: self.input.clone(),
            output: self.output.clone(),
            to: self.to,
            allow_gaps: self.allow_gaps,
            force: self.force,
        }
    }
}

fn convert(a: &ConvertArgs) -> Result<(), CliError> {
    eprint!("{}", super::convert::run(&a.request(), &Silent)?);
    Ok(())
}
