//! One jump as `sandjumper jump` runs it: a typed request, [`run`], and an outcome that
//! serialises to `summary.json`, prints as the human summary and writes its folder.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Serialize, Serializer};

use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::jump::{JumpSpec, simulate_jump};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::record::JumpSummary;
use sandjumper_model::resolve::{ParamsFile, resolve_params};
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::plot::save_figure;
use sandjumper_output::{Progress, StagedDir};
#[cfg(feature = "rig")]
use sandjumper_rig::hil::rig_model::RigModelConfig;
#[cfg(feature = "rig")]
use sandjumper_rig::stroke_table::{RigLimits, StrokeTable};

use crate::StudyError;
use crate::jump_figure::JumpFigure;
use crate::series::write_series_csv;

/// A jump: a one-cycle sine of `kind` at `freq_hz` or, with `stroke`, a stroke file.
#[derive(Debug, Clone, PartialEq)]
pub struct JumpRequest {
    /// Jump kind (ignored with `stroke`).
    pub kind: JumpKind,
    /// Forcing frequency f of the one-cycle sine, Hz (ignored with `stroke`; the command
    /// line has no default).
    pub freq_hz: f64,
    /// Delay of the delayed stutter between its halves, s (None: 0).
    pub tau_s: Option<f64>,
    /// A stroke file (`t_s,p_m` at a fixed rate) run instead of a sine, refused when it fails
    /// the rig's feasibility check.
    pub stroke: Option<PathBuf>,
    /// Ground model.
    pub model: ModelName,
    /// Packing fraction phi of the sand (presets 0.57..=0.62).
    pub phi: f64,
    /// Parameter overrides on top of the `phi` preset.
    pub params: Option<ParamsFile>,
    /// Relative tolerance of the Dormand-Prince 5(4) integrator.
    pub rtol: f64,
    /// Keep every output step (`trajectory.csv`, the figure); [`JumpOutcome::write`] needs it.
    pub record_series: bool,
}

impl Default for JumpRequest {
    fn default() -> Self {
        Self {
            kind: JumpKind::Single,
            freq_hz: 10.0,
            tau_s: None,
            stroke: None,
            model: ModelName::Eq4,
            phi: 0.57,
            params: None,
            rtol: 1e-8,
            record_series: false,
        }
    }
}

impl JumpRequest {
    /// The resolved parameters (the `phi` preset with the overrides on top, validated).
    pub fn resolved_params(&self) -> Result<Params, StudyError> {
        Ok(resolve_params(self.phi, self.params.as_ref())?)
    }

    /// Refuse bad parameters before anything runs (what the command line checks before it
    /// touches an output folder).
    pub fn validate(&self) -> Result<(), StudyError> {
        self.resolved_params().map(drop)
    }

    fn spec(&self) -> JumpSpec {
        JumpSpec {
            kind: self.kind,
            freq_hz: self.freq_hz,
            tau_s: self.tau_s.unwrap_or(0.0),
            model: self.model,
        }
    }
}

/// The stroke file `path`, checked by the rig's feasibility check for `params`' robot
/// ([`StrokeTable::check`]) with a table rate that divides the control rate. Every failure is
/// an input error naming the file.
#[cfg(feature = "rig")]
pub fn checked_stroke(path: &Path, params: &Params) -> Result<StrokeTable, StudyError> {
    let table = StrokeTable::read_csv(path).map_err(StudyError::Input)?;
    table
        .period_ticks(RigModelConfig::default().tick_hz)
        .map_err(|e| StudyError::input(format!("{}: {e}", path.display())))?;
    table.check(&RigLimits::of(params)).map_err(|e| {
        StudyError::input(format!(
            "{}: refused before anything ran: {e}",
            path.display()
        ))
    })?;
    Ok(table)
}

/// A simulated jump: the request as run, the resolved parameters and the simulation's
/// outcome. Serialises to `summary.json` (`jump --json`), displays as the human summary.
#[derive(Debug, Clone)]
pub struct JumpOutcome {
    /// Parameters after the preset and the overrides.
    pub params: Params,
    /// Kind, frequency, delay and model.
    pub spec: JumpSpec,
    /// The stroke file run instead of a sine.
    pub stroke: Option<PathBuf>,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Title of the summary and the figure.
    pub title: String,
    /// Metrics, series (when recorded) and warnings.
    pub simulated: sandjumper_model::jump::JumpOutcome,
}

/// Simulate the jump `request` asks for. A note goes to `progress` when `tau_s` is given
/// for a kind without a delay.
pub fn run(request: &JumpRequest, progress: &dyn Progress) -> Result<JumpOutcome, StudyError> {
    run_with_params(request, request.resolved_params()?, progress)
}

/// [`run`], writing the jump's folder into `out` when given (created, or replacing an earlier
/// sandjumper output; set [`JumpRequest::record_series`] for its series): bad parameters are
/// refused before `out` is touched, an unwritable `out` before the jump runs. The outcome and
/// the folder written.
pub fn run_into(
    request: &JumpRequest,
    out: Option<&Path>,
    progress: &dyn Progress,
) -> Result<(JumpOutcome, Option<PathBuf>), StudyError> {
    request.validate()?;
    let staged = out.map(StagedDir::create).transpose()?;
    let outcome = run(request, progress)?;
    let dir = commit_into(staged, |s| outcome.write_into(s))?;
    Ok((outcome, dir))
}

/// Write a folder being staged (when there is one) with `write`, then give it its name.
pub(crate) fn commit_into(
    staged: Option<StagedDir>,
    write: impl FnOnce(&StagedDir) -> Result<(), StudyError>,
) -> Result<Option<PathBuf>, StudyError> {
    let Some(staged) = staged else {
        return Ok(None);
    };
    write(&staged)?;
    Ok(Some(staged.commit()?))
}

/// [`run`] with parameters resolved by the caller (`request.phi` and `request.params` are not
/// read).
pub fn run_with_params(
    request: &JumpRequest,
    params: Params,
    progress: &dyn Progress,
) -> Result<JumpOutcome, StudyError> {
    if request.stroke.is_none()
        && request.kind != JumpKind::DelayedStutter
        && request.tau_s.is_some_and(|t| t != 0.0)
    {
        progress.note(&format!(
            "warning: --tau {} is ignored: only --kind delayed has a delay",
            request.tau_s.unwrap_or(0.0)
        ));
    }
    let spec = request.spec();
    let opts = SimOptions {
        rtol: request.rtol,
        record_series: request.record_series,
        ..SimOptions::default()
    };
    let simulated = match &request.stroke {
        None => simulate_jump(&params, &spec, &opts),
        #[cfg(feature = "rig")]
        Some(path) => {
            let table = checked_stroke(path, &params)?;
            let stroke = table.kinematic_stroke().map_err(StudyError::Input)?;
            sandjumper_model::jump::simulate_stroke(&params, spec.model, stroke, &opts)
        }
        #[cfg(not(feature = "rig"))]
        Some(_) => return Err(StudyError::Input(crate::error::without_rig("--stroke"))),
    }
    .map_err(|e| StudyError::input(format!("simulation of the jump failed: {e}")))?;
    let phi = params.sand.packing_fraction;
    let title = match &request.stroke {
        Some(path) => format!("stroke {}, model {}, φ = {phi}", path.display(), spec.model),
        None => jump_title(&spec, phi),
    };
    Ok(JumpOutcome {
        params,
        spec,
        stroke: request.stroke.clone(),
        rtol: opts.rtol,
        title,
        simulated,
    })
}

/// Title naming a jump: kind, frequency, delay, model, packing fraction.
pub fn jump_title(spec: &JumpSpec, phi: f64) -> String {
    let kind = match spec.kind {
        JumpKind::Single => "single jump".to_string(),
        JumpKind::Stutter => "stutter jump".to_string(),
        JumpKind::DelayedStutter => format!("delayed stutter (τ = {} s)", spec.tau_s),
    };
    format!(
        "{kind}, f = {} Hz, model {}, φ = {phi}",
        spec.freq_hz, spec.model
    )
}

/// `summary.json`'s object: the request, then every metric of [`JumpSummary`] at top level,
/// then the warnings.
#[derive(Serialize)]
struct Report<'a> {
    kind: &'static str,
    model: &'static str,
    phi: f64,
    freq_hz: Option<f64>,
    tau_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stroke: Option<String>,
    rtol: f64,
    #[serde(flatten)]
    summary: &'a JumpSummary,
    #[serde(skip_serializing_if = "Option::is_none")]
    final_jump_note: Option<&'static str>,
    warnings: &'a [String],
}

impl Serialize for JumpOutcome {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let sine = self.stroke.is_none();
        Report {
            kind: if sine {
                kind_name(self.spec.kind)
            } else {
                "stroke"
            },
            model: self.spec.model.as_str(),
            phi: self.params.sand.packing_fraction,
            freq_hz: sine.then_some(self.spec.freq_hz),
            tau_s: sine.then_some(self.spec.tau_s),
            stroke: self.stroke.as_ref().map(|p| p.display().to_string()),
            rtol: self.rtol,
            summary: &self.simulated.summary,
            final_jump_note: self.simulated.summary.final_height_note(),
            warnings: &self.simulated.warnings,
        }
        .serialize(s)
    }
}

impl JumpOutcome {
    /// `summary.json`'s text (pretty-printed JSON, what `jump --json` prints).
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
        write_jump_files(
            staged,
            &self.title,
            &self.params,
            &self.json()?,
            &self.simulated,
        )
    }
}

impl fmt::Display for JumpOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&human_summary(&self.title, &self.simulated))
    }
}

/// `value` as pretty-printed JSON (an encoding failure is internal).
pub(crate) fn to_json(value: &impl Serialize) -> Result<String, StudyError> {
    serde_json::to_string_pretty(value)
        .map_err(|e| StudyError::internal(format!("cannot encode the summary as JSON: {e}")))
}

/// A jump's human summary under `title` (also `replay`'s first lines).
pub fn human_summary(title: &str, out: &sandjumper_model::jump::JumpOutcome) -> String {
    let s = &out.summary;
    let mut t = format!("{title}\n");
    let mm = |v: f64| format!("{:.2} mm", 1e3 * v);
    t += &format!(
        "  jump height        {}  (apex at t = {:.4} s)\n",
        mm(s.jump_height_m),
        s.apex_time_s
    );
    t += &format!(
        "  final jump height  {}  (after the push-off half begins; apex at t = {:.4} s)\n",
        mm(s.final_jump_height_m),
        s.final_apex_time_s
    );
    if let Some(note) = s.final_height_note() {
        t += &format!("                     {note}\n");
    }
    t += &format!("  max depth          {}\n", mm(s.max_depth_m));
    t += &format!("  peak added mass    {:.1} g\n", 1e3 * s.peak_added_mass_kg);
    t += &match s.liftoff_time_s {
        Some(tl) => format!("  first lift-off     t = {tl:.4} s\n"),
        None => "  first lift-off     never (the foot did not leave the ground)\n".to_string(),
    };
    t += &format!("  peak motor force   {:.1} N\n", s.peak_motor_force_n);
    let mut counts: Vec<(String, usize)> = Vec::new();
    for e in &s.events {
        let k = e.kind.to_string();
        match counts.iter_mut().find(|c| c.0 == k) {
            Some(c) => c.1 += 1,
            None => counts.push((k, 1)),
        }
    }
    let counts: Vec<String> = counts.iter().map(|(k, n)| format!("{n} {k}")).collect();
    t += &format!(
        "  events             {} ({})\n",
        s.events.len(),
        counts.join(", ")
    );
    t += &format!(
        "  integration        {} rhs evaluations, {} steps ({} rejected), run ends at t = {:.4} s\n",
        s.rhs_evaluations, s.steps_accepted, s.steps_rejected, s.end_time_s
    );
    t
}

/// Write a jump's files into a staged output directory: trajectory.csv, params.toml,
/// summary.json (`json`), jump.png and jump.svg (also `replay`'s).
pub fn write_jump_files(
    staged: &StagedDir,
    title: &str,
    params: &Params,
    json: &str,
    outcome: &sandjumper_model::jump::JumpOutcome,
) -> Result<(), StudyError> {
    write_series_csv(&staged.file("trajectory.csv"), &outcome.series)?;
    staged.write_text("params.toml", &params.to_toml())?;
    staged.write_text("summary.json", &format!("{json}\n"))?;
    let fig = JumpFigure {
        title: title.to_string(),
        rows: &outcome.series,
        summary: &outcome.summary,
    };
    save_figure(
        &fig,
        &staged.file("jump.png"),
        Some(&staged.file("jump.svg")),
    )?;
    Ok(())
}
