//! `sandjumper jump`: one jump, a summary or JSON, and with `--out` its files and figure.

use crate::command::CliError;
use crate::command::args::{KindArg, ModelArg, ParamSource, parse_freq, parse_phi, parse_tau};
use crate::command::progress::Bars;
use clap::Args;
use sandjumper_model::resolve::ParamsFile;
use sandjumper_study::StudyError;
use sandjumper_study::jump::{self, JumpRequest};
use std::path::PathBuf;

/// `sandjumper jump`.
#[derive(Debug, Clone, Args)]
pub struct JumpArgs {
    /// Jump kind.
    #[arg(long, value_enum, required_unless_present = "stroke")]
    pub kind: Option<KindArg>,
    /// Forcing frequency f of the one-cycle sine, Hz.
    #[arg(long, value_name = "HZ", value_parser = parse_freq, allow_negative_numbers = true,
          required_unless_present = "stroke")]
    pub freq: Option<f64>,
    /// Drive the jump with a stroke file instead of a one-cycle sine (`t_s,p_m` at a fixed
    /// rate, e.g. `sandjumper optimize`'s stroke.csv), interpolated as the controller replays
    /// it. Refused when it fails the rig's feasibility check.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["kind", "freq", "tau"])]
    pub stroke: Option<PathBuf>,
    /// Delay of the delayed stutter between its halves, s (required with --kind delayed).
    #[arg(long, value_name = "S", value_parser = parse_tau, required_if_eq("kind", "delayed"), allow_negative_numbers = true)]
    pub tau: Option<f64>,
    /// Ground model.
    #[arg(long, value_enum, default_value = "eq4")]
    pub model: ModelArg,
    /// Packing fraction phi of the sand (presets 0.57..=0.62).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = parse_phi, allow_negative_numbers = true)]
    pub phi: f64,
    /// Parameters and integration.
    #[command(flatten)]
    pub source: ParamSource,
    /// Write trajectory.csv, params.toml, summary.json, jump.png and jump.svg into DIR
    /// (created, or replaced if it holds an earlier sandjumper output).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
}

impl JumpArgs {
    /// The library's request for these arguments (`params`: the `--params` file, read).
    pub fn request(&self, params: Option<ParamsFile>, record_series: bool) -> JumpRequest {
        JumpRequest {
            kind: self.kind.unwrap_or(KindArg::Single).into(),
            freq_hz: self.freq.unwrap_or(0.0),
            tau_s: self.tau,
            stroke: self.stroke.clone(),
            model: self.model.into(),
            phi: self.phi,
            params,
            rtol: self.source.rtol,
            record_series,
        }
    }
}

/// Run `jump`.
pub fn run(a: &JumpArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref()).map_err(StudyError::from)?;
    let request = a.request(file, a.out.is_some());
    let (outcome, dir) = jump::run_into(&request, a.out.as_deref(), &Bars::default())?;
    let warnings = &outcome.simulated.warnings;
    super::print_jump(dir, a.json, &outcome.json()?, &outcome, warnings);
    Ok(())
}
