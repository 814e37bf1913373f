//! `sandjumper replay LOG`: an acquisition log's encoder record drives the kinematic
//! simulation (the paper's method); reports what `sandjumper jump` reports, how the stroke
//! was made, and predicted vs measured when the log has measurements.

use std::path::{Path, PathBuf};

use clap::Args;
use serde::Serialize;

use crate::command::args::{ModelArg, ParamSource};
use crate::command::resolve::{ParamsFile, resolve_params};
use crate::study::jump_command::{human_summary, write_jump_files};
use sandjumper_acqlog::{AcqLog, ReadOptions};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::ModelName;
use sandjumper_model::record::JumpSummary;
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_study::replay::{DEFAULT_WINDOW_S, MeasuredComparison, ReplayInfo, replay_log};

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

/// The JSON object of `replay --json` and `summary.json`.
#[derive(Debug, Serialize)]
pub struct ReplayReport<'a> {
    /// The log replayed.
    pub log: String,
    /// Ground model.
    pub model: &'static str,
    /// Packing fraction used.
    pub phi: f64,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// How the stroke was made from the log.
    pub replay: &'a ReplayInfo,
    /// Metrics (the same as `sandjumper jump`).
    #[serde(flatten)]
    pub summary: &'a JumpSummary,
    /// Predicted vs measured, when the log has measurements.
    pub measured: Option<&'a MeasuredComparison>,
    /// Warnings.
    pub warnings: &'a [String],
}

/// Reads a CSV log for the CLI: errors name the file and line (exit 2).
pub fn read_log_file(path: &Path, allow_gaps: bool) -> Result<AcqLog, CliError> {
    let opts = ReadOptions {
        allow_gaps,
        ..ReadOptions::default()
    };
    AcqLog::read_file(path, &opts)
        .map_err(|e| CliError::input(format!("log `{}`: {e}", path.display())))
}

/// One replay as `sandjumper replay` runs it: the resolved parameters, the replay, the JSON
/// object `replay --json` prints and the title of its summary.
pub struct ReplayRun {
    /// Parameters after the preset and the overrides.
    pub params: sandjumper_model::params::Params,
    /// The replay and its outcome.
    pub replayed: sandjumper_study::replay::ReplayOutcome,
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
    let phi = match (a.phi, log.meta.phi) {
        (Some(phi), _) => phi,
        (None, Some(phi)) => phi,
        (None, None) => {
            return Err(CliError::input(format!(
                "log `{}` has no `phi` metadata: give the packing fraction with --phi",
                a.log.display()
            )));
        }
    };
    let params = resolve_params(phi, file)?;
    let model: ModelName = a.model.into();
    let opts = SimOptions {
        rtol: a.source.rtol,
        record_series,
        ..SimOptions::default()
    };
    let replayed = replay_log(log, &params, model, a.window_ms * 1e-3, &opts)
        .map_err(|e| CliError::input(format!("log `{}`: {e}", a.log.display())))?;
    let outcome = &replayed.outcome;
    let report = ReplayReport {
        log: a.log.display().to_string(),
        model: model.as_str(),
        phi: params.sand.packing_fraction,
        rtol: opts.rtol,
        replay: &replayed.info,
        summary: &outcome.summary,
        measured: replayed.measured.as_ref(),
        warnings: &outcome.warnings,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary as JSON: {e}")))?;
    let name = a.log.file_name().map_or_else(
        || a.log.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let title = format!(
        "replay of {name}, model {model}, φ = {}",
        params.sand.packing_fraction
    );
    Ok(ReplayRun {
        params,
        replayed,
        json,
        title,
    })
}

/// Run `replay`.
pub fn run(a: &ReplayArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref())?;
    // The log is checked before an output directory is touched.
    let log = read_log_file(&a.log, a.allow_gaps)?;
    let staged = a.out.as_deref().map(StagedDir::create).transpose()?;
    let ReplayRun {
        params,
        replayed,
        json,
        title,
    } = replay_run(a, &log, file.as_ref(), staged.is_some())?;
    let outcome = &replayed.outcome;
    if let Some(staged) = staged {
        write_jump_files(&staged, &title, &params, &json, outcome)?;
        let dir = staged.commit()?;
        eprintln!(
            "wrote {}/ (trajectory.csv, params.toml, summary.json, jump.png, jump.svg)",
            dir.display()
        );
    }
    if a.json {
        println!("{json}");
    } else {
        print!("{}", human_summary(&title, outcome));
        print!("{}", stroke_lines(&replayed.info));
        if let Some(m) = &replayed.measured {
            print!("{}", measured_lines(m));
        }
    }
    for w in &outcome.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}

fn stroke_lines(i: &ReplayInfo) -> String {
    let mut t = format!(
        "  replayed log       {} samples at {:.3} Hz (rate_hz {}), log time {:.6} s is t = 0, ends at t = {:.4} s\n",
        i.samples, i.grid_rate_hz, i.rate_hz, i.log_start_s, i.log_end_s
    );
    t += &format!(
        "  p'' method         Savitzky-Golay, order {}, window {} samples ({:.2} ms), -3 dB at {:.0} Hz; peak |p''| {:.1} m/s^2\n",
        i.polynomial_order,
        i.window_samples,
        i.window_s * 1e3,
        i.cutoff_hz,
        i.peak_accel_m_s2
    );
    if i.interpolated_samples > 0 {
        t += &format!(
            "  gaps               {} sample(s) interpolated (--allow-gaps)\n",
            i.interpolated_samples
        );
    }
    t
}

fn measured_lines(m: &MeasuredComparison) -> String {
    let mut t = String::new();
    if let Some(measured) = m.measured_jump_height_m {
        t += &format!(
            "  predicted vs measured jump height  {:.2} mm vs {:.2} mm",
            1e3 * m.predicted_jump_height_m,
            1e3 * measured
        );
        if let Some(r) = m.jump_height_relative_error {
            t += &format!(" ({:+.1} %)", 100.0 * r);
        }
        t += "\n";
    }
    if let Some(rms) = m.rod_height_rms_error_m {
        t += &format!(
            "  rod height         RMS predicted - measured {:.2} mm over {} camera samples (highest measured {:.2} mm)\n",
            1e3 * rms,
            m.rod_height_samples,
            1e3 * m.max_measured_rod_height_m.unwrap_or(0.0)
        );
    }
    t
}
