//! `sandjumper replay LOG` as one call: a typed request, [`run`], and an outcome that
//! serialises to `summary.json`, prints as the human summary and writes its folder.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{DEFAULT_WINDOW_S, MeasuredComparison, ReplayInfo, Replayed, replay_log};
use crate::StudyError;
use crate::jump::{commit_into, human_summary, to_json, write_jump_files};
use sandjumper_acqlog::{AcqLog, ReadOptions};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::record::JumpSummary;
use sandjumper_model::resolve::{ParamsFile, resolve_params};
use sandjumper_output::{Progress, StagedDir};

/// A replay of an acquisition log (CSV) through the kinematic simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayRequest {
    /// The acquisition log (CSV).
    pub log: PathBuf,
    /// Ground model.
    pub model: ModelName,
    /// Packing fraction (None: the log's `phi` metadata).
    pub phi: Option<f64>,
    /// Parameter overrides on top of the preset.
    pub params: Option<ParamsFile>,
    /// Relative tolerance of the integrator.
    pub rtol: f64,
    /// Savitzky-Golay window for p'' (cubic), s.
    pub window_s: f64,
    /// Accept missing samples in the log and interpolate them (reported).
    pub allow_gaps: bool,
    /// Keep every output step (`trajectory.csv`, the figure); [`ReplayOutcome::write`] needs it.
    pub record_series: bool,
}

impl Default for ReplayRequest {
    fn default() -> Self {
        Self {
            log: PathBuf::new(),
            model: ModelName::Eq4,
            phi: None,
            params: None,
            rtol: 1e-8,
            window_s: DEFAULT_WINDOW_S,
            allow_gaps: false,
            record_series: false,
        }
    }
}

/// Value parser: the Savitzky-Golay window in milliseconds, 0 < ms <= 1000 (the command
/// line's `--window-ms`; [`ReplayRequest::window_s`] is this / 1000).
pub fn parse_window_ms(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1000.0 => Ok(v),
        _ => Err(format!(
            "`{s}` is not a window length: a number of milliseconds in (0, 1000]"
        )),
    }
}

impl ReplayRequest {
    /// Read the log; errors name the file and line (the caller's input).
    pub fn read_log(&self) -> Result<AcqLog, StudyError> {
        let opts = ReadOptions {
            allow_gaps: self.allow_gaps,
            ..ReadOptions::default()
        };
        AcqLog::read_file(&self.log, &opts)
            .map_err(|e| StudyError::input(format!("log `{}`: {e}", self.log.display())))
    }
}

/// A replayed log: the request as run, the resolved parameters and the replay. Serialises to
/// `summary.json` (`replay --json`), displays as the human summary.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayOutcome {
    /// The log replayed.
    pub log: String,
    /// Ground model.
    pub model: &'static str,
    /// Packing fraction used.
    pub phi: f64,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// How the stroke was made from the log.
    pub replay: ReplayInfo,
    /// Metrics (the same as `sandjumper jump`).
    #[serde(flatten)]
    pub summary: JumpSummary,
    /// Predicted vs measured, when the log has measurements.
    pub measured: Option<MeasuredComparison>,
    /// Warnings.
    pub warnings: Vec<String>,
    /// Parameters after the preset and the overrides.
    #[serde(skip)]
    pub params: Params,
    /// Title of the summary and the figure.
    #[serde(skip)]
    pub title: String,
    /// The replay and its simulation.
    #[serde(skip)]
    pub replayed: Replayed,
}

/// Read the log `request` names and replay it.
pub fn run(request: &ReplayRequest, progress: &dyn Progress) -> Result<ReplayOutcome, StudyError> {
    run_log(request, &request.read_log()?, progress)
}

/// [`run`], writing the replay's folder into `out` when given (as
/// [`ReplayOutcome::write`]; set [`ReplayRequest::record_series`] for its series): the log is
/// checked before `out` is touched. The outcome and the folder written.
pub fn run_into(
    request: &ReplayRequest,
    out: Option<&Path>,
    progress: &dyn Progress,
) -> Result<(ReplayOutcome, Option<PathBuf>), StudyError> {
    let log = request.read_log()?;
    let staged = out.map(StagedDir::create).transpose()?;
    let outcome = run_log(request, &log, progress)?;
    let dir = commit_into(staged, |s| outcome.write_into(s))?;
    Ok((outcome, dir))
}

/// Replay `log` (read from `request.log`) as `request` asks.
pub fn run_log(
    request: &ReplayRequest,
    log: &AcqLog,
    _progress: &dyn Progress,
) -> Result<ReplayOutcome, StudyError> {
    let name = request.log.display();
    let phi = request.phi.or(log.meta.phi).ok_or_else(|| {
        StudyError::input(format!(
            "log `{name}` has no `phi` metadata: give the packing fraction with --phi"
        ))
    })?;
    let params = resolve_params(phi, request.params.as_ref())?;
    let opts = SimOptions {
        rtol: request.rtol,
        record_series: request.record_series,
        ..SimOptions::default()
    };
    let replayed = replay_log(log, &params, request.model, request.window_s, &opts)
        .map_err(|e| StudyError::input(format!("log `{name}`: {e}")))?;
    let file_name = request
        .log
        .file_name()
        .map_or_else(|| name.to_string(), |n| n.to_string_lossy().into_owned());
    let phi = params.sand.packing_fraction;
    Ok(ReplayOutcome {
        log: name.to_string(),
        model: request.model.as_str(),
        phi,
        rtol: opts.rtol,
        replay: replayed.info.clone(),
        summary: replayed.outcome.summary.clone(),
        measured: replayed.measured.clone(),
        warnings: replayed.outcome.warnings.clone(),
        title: format!("replay of {file_name}, model {}, φ = {phi}", request.model),
        params,
        replayed,
    })
}

impl ReplayOutcome {
    /// `summary.json`'s text (pretty-printed JSON, what `replay --json` prints).
    pub fn json(&self) -> Result<String, StudyError> {
        to_json(self)
    }

    /// Write trajectory.csv, params.toml, summary.json, jump.png and jump.svg into `dir`
    /// (created, or replacing an earlier sandjumper output); the folder written.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, StudyError> {
        let staged = StagedDir::create(dir)?;
        self.write_into(&staged)?;
        Ok(staged.commit()?)
    }

    /// Write the files of [`write`](Self::write) into a folder being staged.
    pub fn write_into(&self, staged: &StagedDir) -> Result<(), StudyError> {
        let json = self.json()?;
        write_jump_files(
            staged,
            &self.title,
            &self.params,
            &json,
            &self.replayed.outcome,
        )
    }
}

impl fmt::Display for ReplayOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&human_summary(&self.title, &self.replayed.outcome))?;
        f.write_str(&stroke_lines(&self.replay))?;
        if let Some(m) = &self.measured {
            f.write_str(&measured_lines(m))?;
        }
        Ok(())
    }
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
