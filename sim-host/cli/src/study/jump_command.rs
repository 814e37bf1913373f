//! `sandjumper jump`: one jump, a summary or JSON, and with `--out` its files and figure.

use serde::Serialize;

use crate::command::args::{KindArg, ModelArg, ParamSource, parse_freq, parse_phi, parse_tau};
use crate::command::resolve::{ParamsFile, resolve_params};
use crate::command::stroke::checked_stroke;
use clap::Args;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::jump::{JumpOutcome, JumpSpec, simulate_jump, simulate_stroke};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::ModelName;
use sandjumper_model::record::JumpSummary;
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_output::plot::save_figure;
use sandjumper_study::jump_figure::JumpFigure;
use sandjumper_study::series::write_series_csv;
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

/// The JSON object of `jump --json` and `summary.json`: the request, then every metric of
/// [`JumpSummary`] at top level, then the warnings.
#[derive(Debug, Serialize)]
pub struct JumpReport<'a> {
    /// `single`, `stutter` or `delayed`.
    pub kind: &'static str,
    /// Ground model.
    pub model: &'static str,
    /// Packing fraction used (from the resolved parameters).
    pub phi: f64,
    /// Forcing frequency, Hz (null for a stroke file).
    pub freq_hz: Option<f64>,
    /// Delay, s (null for a stroke file).
    pub tau_s: Option<f64>,
    /// The stroke file run instead of a sine.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stroke: Option<String>,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Metrics.
    #[serde(flatten)]
    pub summary: &'a JumpSummary,
    /// What a final jump height that is not positive means, in words (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_jump_note: Option<&'static str>,
    /// Warnings (e.g. motor force above its peak).
    pub warnings: &'a [String],
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

pub(crate) fn human_summary(title: &str, out: &JumpOutcome) -> String {
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
/// summary.json (`json`), jump.png and jump.svg (also used by `replay`).
pub(crate) fn write_jump_files(
    staged: &StagedDir,
    title: &str,
    params: &sandjumper_model::params::Params,
    json: &str,
    outcome: &JumpOutcome,
) -> Result<(), CliError> {
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

/// One jump as `sandjumper jump` runs it: the resolved parameters, the request, the outcome
/// and the JSON object `jump --json` prints.
pub struct JumpRun {
    /// Parameters after the preset and the overrides.
    pub params: sandjumper_model::params::Params,
    /// Kind, frequency, delay and model.
    pub spec: JumpSpec,
    /// The simulation's outcome (with its series when asked for).
    pub outcome: JumpOutcome,
    /// `jump --json`'s object, pretty-printed.
    pub json: String,
}

/// Simulate the jump `a` asks for with `params` (resolved from `a.phi` and the overrides by
/// [`resolve_params`]; `a.source.params` is not read here); `record_series` keeps every
/// output step (`trajectory.csv`). Errors are the CLI's.
pub fn simulate_run(
    a: &JumpArgs,
    params: sandjumper_model::params::Params,
    record_series: bool,
) -> Result<JumpRun, CliError> {
    let kind: JumpKind = a.kind.unwrap_or(KindArg::Single).into();
    let model: ModelName = a.model.into();
    let spec = JumpSpec {
        kind,
        freq_hz: a.freq.unwrap_or(0.0),
        tau_s: a.tau.unwrap_or(0.0),
        model,
    };
    let opts = SimOptions {
        rtol: a.source.rtol,
        record_series,
        ..SimOptions::default()
    };
    let outcome = match &a.stroke {
        None => simulate_jump(&params, &spec, &opts),
        Some(path) => {
            let table = checked_stroke(path, &params)?;
            let stroke = table.kinematic_stroke().map_err(CliError::input)?;
            simulate_stroke(&params, model, stroke, &opts)
        }
    }
    .map_err(|e| CliError::input(format!("simulation of the jump failed: {e}")))?;
    let report = JumpReport {
        kind: if a.stroke.is_some() {
            "stroke"
        } else {
            kind_name(kind)
        },
        model: model.as_str(),
        phi: params.sand.packing_fraction,
        freq_hz: a.stroke.is_none().then_some(spec.freq_hz),
        tau_s: a.stroke.is_none().then_some(spec.tau_s),
        stroke: a.stroke.as_ref().map(|p| p.display().to_string()),
        rtol: opts.rtol,
        summary: &outcome.summary,
        final_jump_note: outcome.summary.final_height_note(),
        warnings: &outcome.warnings,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary as JSON: {e}")))?;
    Ok(JumpRun {
        params,
        spec,
        outcome,
        json,
    })
}

/// Run `jump`.
pub fn run(a: &JumpArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref())?;
    // Bad parameters are refused before an output directory is touched.
    let params = resolve_params(a.phi, file.as_ref())?;
    if a.kind != Some(KindArg::Delayed) && a.tau.is_some_and(|t| t != 0.0) {
        eprintln!(
            "warning: --tau {} is ignored: only --kind delayed has a delay",
            a.tau.unwrap_or(0.0)
        );
    }
    // Fail on an unwritable output directory before spending time on the simulation.
    let staged = a.out.as_deref().map(StagedDir::create).transpose()?;
    let JumpRun {
        params,
        spec,
        outcome,
        json,
    } = simulate_run(a, params, staged.is_some())?;
    let phi = params.sand.packing_fraction;
    let title = match &a.stroke {
        Some(path) => format!("stroke {}, model {}, φ = {phi}", path.display(), spec.model),
        None => jump_title(&spec, phi),
    };
    if let Some(staged) = staged {
        write_jump_files(&staged, &title, &params, &json, &outcome)?;
        let dir = staged.commit()?;
        eprintln!(
            "wrote {}/ (trajectory.csv, params.toml, summary.json, jump.png, jump.svg)",
            dir.display()
        );
    }
    if a.json {
        println!("{json}");
    } else {
        print!("{}", human_summary(&title, &outcome));
    }
    for w in &outcome.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}
