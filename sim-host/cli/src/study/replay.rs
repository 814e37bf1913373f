//! `sandjumper replay LOG`: an acquisition log's encoder record drives the kinematic
//! simulation (the paper's method); reports what `sandjumper jump` reports, how the stroke
//! was made, and predicted vs measured when the log has measurements.

use std::path::PathBuf;

use clap::Args;

use crate::command::CliError;
use crate::command::args::{ModelArg, ParamSource};
use crate::command::progress::Bars;
use sandjumper_model::resolve::ParamsFile;
use sandjumper_study::StudyError;
use sandjumper_study::replay::{self, DEFAULT_WINDOW_S, ReplayRequest, parse_window_ms};

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

impl ReplayArgs {
    /// The library's request for these arguments (`params`: the `--params` file, read).
    pub fn request(&self, params: Option<ParamsFile>, record_series: bool) -> ReplayRequest {
        ReplayRequest {
            log: self.log.clone(),
            model: self.model.into(),
            phi: self.phi,
            params,
            rtol: self.source.rtol,
            window_s: self.window_ms * 1e-3,
            allow_gaps: self.allow_gaps,
            record_series,
        }
    }
}

/// Run `replay`.
pub fn run(a: &ReplayArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref()).map_err(StudyError::from)?;
    let request = a.request(file, a.out.is_some());
    let (outcome, dir) = replay::run_into(&request, a.out.as_deref(), &Bars::default())?;
    super::print_jump(dir, a.json, &outcome.json()?, &outcome, &outcome.warnings);
    Ok(())
}
