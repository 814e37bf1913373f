//! The paper's fitting procedure, with eq4 standing in for the experiment (docs/model.md section
//! 3, "alpha for eq1"): eq1's constant `alpha` is fitted per packing fraction to single-jump
//! heights over forcing frequency (the existing `fit drag` code, [`fit_jumps`]), and only then
//! are eq1 and eq4 compared on the other jumps. The paper's finding: fitted to single jumps,
//! eq1 agrees with eq4 on single and delayed-stutter jumps but over-predicts the stutter's
//! push-off at low packing fraction, where the added mass matters; the gap shrinks at high
//! packing fraction.
//!
//! Heights compared: the single and delayed stutter by their jump height, the stutter by its
//! final (push-off) height (its jump height is the preliminary hop's, set by the pull-up half
//! before the laws differ much).

use std::path::Path;

use rayon::prelude::*;
use sandjumper_core::trajectory::JumpKind;
use serde::Serialize;

use super::grid::GridFigure;
use crate::fit::data::{HeightColumn, JumpMeasurement};
use crate::fit::jumps::{DragParam, JumpFitSetup, fit_jumps};
use crate::sweep::drive::jump_metrics;
use crate::sweep::{Combination, SweepDrive};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::{Eq1AlphaChoice, ModelName, Params};
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::plot::lines::{Line, LinePanel};
use sandjumper_output::plot::palette;

/// The preset rows alpha is fitted at.
pub const FIT_PHIS: [f64; 6] = [0.57, 0.58, 0.59, 0.60, 0.61, 0.62];
/// The packing fractions eq1 and eq4 are compared at (the paper's two ends).
pub const COMPARE_PHIS: [f64; 2] = [0.57, 0.62];
/// Delay of the compared delayed stutter, s (as in the other figures).
pub const DELAY_S: f64 = 0.75;
/// Lowest forcing frequency fitted and compared, Hz (docs/model.md section 4 speaks of 4-20 Hz;
/// below, the slow strokes barely lift the robot and carry no information on drag).
pub const FIT_MIN_FREQ_HZ: f64 = 4.0;

/// One fitted alpha.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AlphaRow {
    /// The law whose constant alpha was fitted (`eq1` or `eq1-linear`).
    pub model: &'static str,
    /// Packing fraction.
    pub phi: f64,
    /// docs/model.md's alpha (the table's column), where the fit started, kg/m.
    pub alpha_start_kg_m: f64,
    /// Fitted alpha, kg/m.
    pub alpha_fitted_kg_m: f64,
    /// Its standard error, kg/m.
    pub alpha_stderr_kg_m: f64,
    /// RMS of fitted single-jump heights minus eq4's, mm.
    pub residual_rms_mm: f64,
    /// Single jumps fitted.
    pub jumps: usize,
}

/// Header of `eq1_alpha_fit.csv`.
pub const ALPHA_HEADER: [&str; 7] = [
    "model",
    "phi",
    "alpha_start_kg_m",
    "alpha_fitted_kg_m",
    "alpha_stderr_kg_m",
    "residual_rms_mm",
    "jumps",
];

/// One jump of the comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CompareRow {
    /// `single`, `stutter` or `delayed`.
    pub kind: &'static str,
    /// Packing fraction.
    pub phi: f64,
    /// Forcing frequency, Hz.
    pub freq_hz: f64,
    /// `eq4` or `eq1-fitted`.
    pub model: &'static str,
    /// Jump height, m.
    pub jump_height_m: f64,
    /// Final (push-off) height, m.
    pub final_jump_height_m: f64,
}

/// Header of `eq1_fitted.csv`.
pub const COMPARE_HEADER: [&str; 6] = [
    "kind",
    "phi",
    "freq_hz",
    "model",
    "jump_height_m",
    "final_jump_height_m",
];

/// The compared height of a row: the stutter's push-off, the others' jump height.
pub fn compared_height(row: &CompareRow) -> f64 {
    if row.kind == "stutter" {
        row.final_jump_height_m
    } else {
        row.jump_height_m
    }
}

fn simulate(
    params: &Params,
    kind: JumpKind,
    freq_hz: f64,
    model: ModelName,
    rtol: f64,
) -> Result<(f64, f64), String> {
    let jump = Combination {
        kind,
        model,
        phi: params.sand.packing_fraction,
        freq_hz,
        tau_s: if kind == JumpKind::DelayedStutter {
            DELAY_S
        } else {
            0.0
        },
    };
    let m = jump_metrics(SweepDrive::Kinematic, params, &jump, rtol)
        .map_err(|e| format!("{kind:?} at {freq_hz} Hz, {model}: {e}"))?;
    Ok((m.jump_height_m, m.final_jump_height_m))
}

/// docs/model.md's alpha column at `phi`, kg/m: where the fit starts.
fn starting_alpha(phi: f64) -> Result<f64, String> {
    Params::preset_eq1_alpha(phi, Eq1AlphaChoice::Starting)
        .ok_or_else(|| format!("no preset alpha at phi = {phi}"))
}

fn preset(phi: f64) -> Result<Params, String> {
    Params::preset(phi).map_err(|e| e.to_string())
}

/// Fit `model`'s constant alpha (eq1 or eq1-linear) at every [`FIT_PHIS`] row to eq4's
/// single-jump heights at `freqs_hz`, on the presets.
pub fn fit_alphas(model: ModelName, freqs_hz: &[f64], rtol: f64) -> Result<Vec<AlphaRow>, String> {
    fit_alphas_on(model, &FIT_PHIS, freqs_hz, rtol, &preset)
}

/// Base parameters of both models at a packing fraction.
type ParamsAt<'a> = &'a (dyn Fn(f64) -> Result<Params, String> + Sync);

/// [`fit_alphas`] at `phis` on the parameters `params_at` gives (eq4 with them stands in for
/// the experiment; eq1 is fitted on them, its alpha replaced).
fn fit_alphas_on(
    model: ModelName,
    phis: &[f64],
    freqs_hz: &[f64],
    rtol: f64,
    params_at: ParamsAt,
) -> Result<Vec<AlphaRow>, String> {
    let preset = params_at;
    let jobs: Vec<(f64, f64)> = phis
        .iter()
        .flat_map(|&phi| freqs_hz.iter().map(move |&f| (phi, f)))
        .collect();
    let measured: Vec<JumpMeasurement> = jobs
        .par_iter()
        .enumerate()
        .map(|(k, &(phi, f))| {
            let (h, _) = simulate(&preset(phi)?, JumpKind::Single, f, ModelName::Eq4, rtol)?;
            Ok(JumpMeasurement {
                kind: JumpKind::Single,
                phi,
                freq_hz: f,
                tau_s: 0.0,
                height_m: h,
                line: k as u64 + 1,
            })
        })
        .collect::<Result<_, String>>()?;
    // The fit starts from docs/model.md's alpha column, not from the fitted presets.
    let base = |phi: f64| -> Result<Params, String> {
        let mut p = preset(phi)?;
        p.sand.alpha_kg_m = starting_alpha(phi)?;
        Ok(p)
    };
    let setup = JumpFitSetup {
        param: DragParam::Alpha,
        model,
        height: HeightColumn::Jump,
        sim: SimOptions {
            rtol,
            ..SimOptions::default()
        },
        base: &base,
    };
    // One fit per packing fraction, so each report's residual RMS is that row's.
    phis.iter()
        .map(|&phi| {
            let jumps: Vec<JumpMeasurement> =
                measured.iter().filter(|m| m.phi == phi).copied().collect();
            let report = fit_jumps(
                &jumps,
                Path::new("eq4 single jumps (standing in for the experiment)"),
                &setup,
            )
            .map_err(|e| format!("fitting {model}'s alpha: {e}"))?;
            let fit = report
                .fits
                .first()
                .ok_or_else(|| format!("no fitted alpha at phi = {phi}"))?;
            Ok(AlphaRow {
                model: model.as_str(),
                phi,
                alpha_start_kg_m: starting_alpha(phi)?,
                alpha_fitted_kg_m: fit.value,
                alpha_stderr_kg_m: fit.stderr,
                residual_rms_mm: 1e3 * report.residual_rms,
                jumps: report.points_used,
            })
        })
        .collect()
}

/// eq4 and eq1 with its fitted alpha on single, stutter and delayed-stutter jumps at
/// [`COMPARE_PHIS`] over `freqs_hz`.
pub fn compare(
    alphas: &[AlphaRow],
    freqs_hz: &[f64],
    rtol: f64,
) -> Result<Vec<CompareRow>, String> {
    let kinds = [
        JumpKind::Single,
        JumpKind::Stutter,
        JumpKind::DelayedStutter,
    ];
    compare_on(alphas, &kinds, &COMPARE_PHIS, freqs_hz, rtol, &preset)
}

/// [`compare`] for `kinds` at `phis`, on the parameters `params_at` gives.
fn compare_on(
    alphas: &[AlphaRow],
    kinds: &[JumpKind],
    phis: &[f64],
    freqs_hz: &[f64],
    rtol: f64,
    params_at: ParamsAt,
) -> Result<Vec<CompareRow>, String> {
    let mut jobs = Vec::new();
    for &phi in phis {
        let alpha = alphas
            .iter()
            .find(|a| a.model == "eq1" && (a.phi - phi).abs() < 1e-9)
            .ok_or_else(|| format!("no fitted eq1 alpha at phi = {phi}"))?
            .alpha_fitted_kg_m;
        for &kind in kinds {
            for &f in freqs_hz {
                jobs.push((phi, alpha, kind, f, ModelName::Eq4));
                jobs.push((phi, alpha, kind, f, ModelName::Eq1));
            }
        }
    }
    jobs.par_iter()
        .map(|&(phi, alpha, kind, f, model)| {
            let mut params = params_at(phi)?;
            if model == ModelName::Eq1 {
                params.sand.alpha_kg_m = alpha;
            }
            let (h, fin) = simulate(&params, kind, f, model, rtol)?;
            Ok(CompareRow {
                kind: kind_name(kind),
                phi,
                freq_hz: f,
                model: if model == ModelName::Eq4 {
                    "eq4"
                } else {
                    "eq1-fitted"
                },
                jump_height_m: h,
                final_jump_height_m: fin,
            })
        })
        .collect()
}

/// The best compared height of `kind` at `phi` for `model` over frequency, m.
pub fn best_height(rows: &[CompareRow], kind: &str, phi: f64, model: &str) -> Option<f64> {
    rows.iter()
        .filter(|r| r.kind == kind && r.model == model && (r.phi - phi).abs() < 1e-9)
        .map(compared_height)
        .fold(None, |best, h| Some(best.map_or(h, |b: f64| b.max(h))))
}

/// eq1-fitted over eq4, best compared height over frequency, for each kind and phi: the
/// paper's gap (`kind`, `phi`, ratio).
pub fn gaps(rows: &[CompareRow]) -> Vec<(&'static str, f64, f64)> {
    let mut out = Vec::new();
    for kind in ["single", "stutter", "delayed"] {
        for &phi in &COMPARE_PHIS {
            if let (Some(e1), Some(e4)) = (
                best_height(rows, kind, phi, "eq1-fitted"),
                best_height(rows, kind, phi, "eq4"),
            ) && e4 > 0.0
            {
                out.push((kind, phi, e1 / e4));
            }
        }
    }
    out
}

/// The figure: one panel per kind, eq4 solid and eq1 (fitted) dashed, one colour per phi.
pub fn figure(rows: &[CompareRow]) -> GridFigure {
    let captions = [
        ("single", "single jump"),
        ("stutter", "stutter: push-off (final) height"),
        ("delayed", "delayed stutter, tau = 0.75 s"),
    ];
    let mut panels = Vec::new();
    for (kind, caption) in captions {
        let mut lines = Vec::new();
        for (i, &phi) in COMPARE_PHIS.iter().enumerate() {
            for (model, dashed) in [("eq4", false), ("eq1-fitted", true)] {
                lines.push(Line {
                    label: format!("φ = {phi}, {model}"),
                    points: rows
                        .iter()
                        .filter(|r| r.kind == kind && r.model == model)
                        .filter(|r| (r.phi - phi).abs() < 1e-9)
                        .map(|r| (r.freq_hz, 1e3 * compared_height(r)))
                        .collect(),
                    color: palette(i),
                    dashed,
                    markers: false,
                });
            }
        }
        panels.push(LinePanel {
            caption: caption.into(),
            x_desc: "forcing frequency f (Hz)".into(),
            y_desc: "height (mm)".into(),
            lines,
            y_from_zero: false,
        });
    }
    let fig = GridFigure::row(
        "eq1 with alpha fitted to eq4's single jumps (dashed) vs eq4 (solid)",
        panels,
    );
    GridFigure {
        size: (fig.size.0, fig.size.1 + 30),
        ..fig
    }
}

/// The eq4 parameters whose effect on the gap is asked next (docs/model.md section 3): the
/// added-mass drag factor b, the jamming-front rate mu, the added-mass constant C, the
/// re-intrusion stiffness kappa and length l_re (the last two are shared with eq1: they come
/// from quasi-static intrusion tests in the paper).
pub const SENSITIVITY_PARAMS: [(&str, &str); 5] = [
    ("b", "sand.added_mass_drag_b"),
    ("mu", "sand.jamming_front_rate"),
    ("C", "sand.added_mass_c_m2"),
    ("kappa", "sand.reintrusion_kappa_per_k1"),
    ("l_re", "sand.reintrusion_length_m"),
];
/// The factors each parameter is scaled by (+-20 %).
pub const SENSITIVITY_FACTORS: [f64; 2] = [0.8, 1.2];

fn scale(p: &mut Params, name: &str, factor: f64) {
    let s = &mut p.sand;
    let field = match name {
        "b" => &mut s.added_mass_drag_b,
        "mu" => &mut s.jamming_front_rate,
        "C" => &mut s.added_mass_c_m2,
        "kappa" => &mut s.reintrusion_kappa_per_k1,
        _ => &mut s.reintrusion_length_m,
    };
    *field *= factor;
}

/// One row of the sensitivity table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SensitivityRow {
    /// The eq4 parameter scaled (`none` for the baseline).
    pub param: &'static str,
    /// Its key in a params file.
    pub key: &'static str,
    /// Scale factor.
    pub factor: f64,
    /// Packing fraction.
    pub phi: f64,
    /// eq1's alpha fitted to this eq4's single jumps, kg/m.
    pub alpha_fitted_kg_m: f64,
    /// Best stutter push-off, eq1 fitted over eq4.
    pub stutter_gap: f64,
    /// Change of the gap against the baseline, percentage points.
    pub gap_change_points: f64,
}

/// Header of `eq1_gap_sensitivity.csv`.
pub const SENSITIVITY_HEADER: [&str; 7] = [
    "param",
    "key",
    "factor",
    "phi",
    "alpha_fitted_kg_m",
    "stutter_gap",
    "gap_change_points",
];

/// The stutter gap (eq1 fitted over eq4, best push-off) at `phi` on `params_at`'s parameters,
/// with eq1's alpha fitted there first: (alpha, gap).
fn stutter_gap(
    phi: f64,
    freqs_hz: &[f64],
    rtol: f64,
    params_at: ParamsAt,
) -> Result<(f64, f64), String> {
    let alphas = fit_alphas_on(ModelName::Eq1, &[phi], freqs_hz, rtol, params_at)?;
    let rows = compare_on(
        &alphas,
        &[JumpKind::Stutter],
        &[phi],
        freqs_hz,
        rtol,
        params_at,
    )?;
    let best = |model| {
        best_height(&rows, "stutter", phi, model)
            .ok_or_else(|| format!("no stutter at phi = {phi}"))
    };
    Ok((
        alphas[0].alpha_fitted_kg_m,
        best("eq1-fitted")? / best("eq4")?,
    ))
}

/// Which eq4 parameters move the eq1-vs-eq4 stutter gap, and by how much: each of
/// [`SENSITIVITY_PARAMS`] scaled by each of [`SENSITIVITY_FACTORS`] at [`COMPARE_PHIS`], eq1's
/// alpha refitted every time (the paper's procedure on a different "experiment").
pub fn sensitivity(freqs_hz: &[f64], rtol: f64) -> Result<Vec<SensitivityRow>, String> {
    let mut rows = Vec::new();
    for &phi in &COMPARE_PHIS {
        let (alpha0, gap0) = stutter_gap(phi, freqs_hz, rtol, &preset)?;
        rows.push(SensitivityRow {
            param: "none",
            key: "",
            factor: 1.0,
            phi,
            alpha_fitted_kg_m: alpha0,
            stutter_gap: gap0,
            gap_change_points: 0.0,
        });
        for (param, key) in SENSITIVITY_PARAMS {
            for factor in SENSITIVITY_FACTORS {
                let params_at = move |phi: f64| -> Result<Params, String> {
                    let mut p = preset(phi)?;
                    scale(&mut p, param, factor);
                    p.validate().map_err(|e| e.to_string())?;
                    Ok(p)
                };
                let (alpha, gap) = stutter_gap(phi, freqs_hz, rtol, &params_at)?;
                rows.push(SensitivityRow {
                    param,
                    key,
                    factor,
                    phi,
                    alpha_fitted_kg_m: alpha,
                    stutter_gap: gap,
                    gap_change_points: 100.0 * (gap - gap0),
                });
            }
        }
    }
    Ok(rows)
}
