//! `sandjumper replay LOG`: an acquisition log's encoder record drives the kinematic
//! simulation (the paper's method); reports what `sandjumper jump` reports, how the stroke
//! was made, and predicted vs measured when the log has measurements.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::command::CliError;
use crate::command::args::{ModelArg, ParamSource};
use crate::command::progress::Bars;
use crate::command::resolve::ParamsFile;
use crate::study::cli_error;
use sandjumper_acqlog::AcqLog;
use sandjumper_output::{Silent, StagedDir};
use sandjumper_study::replay::{self, DEFAULT_WINDOW_S, ReplayRequest};

/// `sandjumper replay`.
#[derive(Debug, Clone, Args)]
pub struct ReplayArgs {
    /// The acquisition log (CSV, see README "Acquisition logs"; a binary log must first go
    /// through `sandjumper log convert`).
    #[arg(value_name = "LOG")]
    pub log: PathBuf,
    /// Ground model.
    #[arg(long, value_enum, default_value = "eq4")]
    pub model: ModelArg,
    /// Packing fraction phi of the sand (default: the log's `phi` metadata).
    #[arg(long, value_name = "PHI", value_parser = crate::command::args::parse_phi)]
    pub phi: Option<f64>,
    /// Parameters and integration.
    #[command(flatten)]
    pub source: ParamSource,
    /// Savitzky-Golay window for p'' (cubic), milliseconds.
    #[arg(long, value_name = "MS", default_value_t = DEFAULT_WINDOW_S * 1e3, value_parser = parse_window_ms)]
    pub window_ms: f64,
    /// Accept missing samples in the log and interpolate them (reported).
    #[arg(long)]
    pub allow_gaps: bool,
    /// Write trajectory.csv, params.toml, summary.json, jump.png and jump.svg into DIR.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
}

fn parse_window_ms(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1000.0 => Ok(v),
        _ => Err(format!(
            "`{s}` is not a window length: a number of milliseconds in (0, 1000]"
        )),
    }
}

impl ReplayArgs {
    /// The library's request for these arguments (`params`: the `--params` file, read).
    pub fn request(&self, params: Option<&ParamsFile>, record_series: bool) -> ReplayRequest {
        ReplayRequest {
            log: self.log.clone(),
            model: self.model.into(),
            phi: self.phi,
            params: params.map(ParamsFile::to_library),
            rtol: self.source.rtol,
            window_s: self.window_ms * 1e-3,
            allow_gaps: self.allow_gaps,
            record_series,
        }
    }
}

/// Reads a CSV log for the CLI: errors name the file and line (exit 2).
pub fn read_log_file(path: &Path, allow_gaps: bool) -> Result<AcqLog, CliError> {
    let request = ReplayRequest {
        log: path.to_path_buf(),
        allow_gaps,
        ..ReplayRequest::default()
    };
    request.read_log().map_err(cli_error)
}

/// One replay as `sandjumper replay` runs it: the resolved parameters, the replay, the JSON
/// object `replay --json` prints and the title of its summary.
pub struct ReplayRun {
    /// Parameters after the preset and the overrides.
    pub params: sandjumper_model::params::Params,
    /// The replay and its outcome.
    pub replayed: sandjumper_study::replay::Replayed,
    /// `replay --json`'s object, pretty-printed.
    pub json: String,
    /// Title of the summary and the figure.
    pub title: String,
}

/// Replay `log` (the file `a` names, read by [`read_log_file`]) with the overrides `file` (in
/// place of `a.source.params`, which is not read here); `record_series` keeps every output
/// step (`trajectory.csv`). Errors are the CLI's.
pub fn replay_run(
    a: &ReplayArgs,
    log: &AcqLog,
    file: Option<&ParamsFile>,
    record_series: bool,
) -> Result<ReplayRun, CliError> {
    let out = replay::run_log(&a.request(file, record_series), log, &Silent)?;
    Ok(ReplayRun {
        json: out.json()?,
        params: out.params,
        replayed: out.replayed,
        title: out.title,
    })
}

/// Run `replay`.
pub fn run(a: &ReplayArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref())?;
    let request = a.request(file.as_ref(), a.out.is_some());
    // The log is checked before an output directory is touched.
    let log = request.read_log()?;
    let staged = a.out.as_deref().map(StagedDir::create).transpose()?;
    let outcome = replay::run_log(&request, &log, &Bars::default())?;
    if let Some(staged) = staged {
        outcome.write_into(&staged)?;
        let dir = staged.commit()?;
        eprintln!(
            "wrote {}/ (trajectory.csv, params.toml, summary.json, jump.png, jump.svg)",
            dir.display()
        );
    }
    if a.json {
        println!("{}", outcome.json()?);
    } else {
        print!("{outcome}");
    }
    for w in &outcome.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}
