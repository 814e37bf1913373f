//! Figures 1-3: jump height against packing fraction, against forcing frequency, and the
//! delayed stutter against its delay.

use sandjumper_core::trajectory::JumpKind;

use super::grid::GridFigure;
use super::sweeps::{BestRow, DELAYED_TAU_S, KINDS, LOW_PHI};
use crate::sweep::SweepRow;
use sandjumper_model::params::ModelName;
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::plot::lines::{Line, LinePanel};
use sandjumper_output::plot::palette;

/// Legend name of a jump kind in these figures.
pub fn kind_label(kind: JumpKind) -> String {
    match kind {
        JumpKind::Single => "single".into(),
        JumpKind::Stutter => "stutter".into(),
        JumpKind::DelayedStutter => format!("delayed, τ = {DELAYED_TAU_S} s"),
    }
}

fn is(row_kind: &str, row_model: &str, kind: JumpKind, model: ModelName) -> bool {
    row_kind == kind_name(kind) && row_model == model.as_str()
}

/// Figure 1: best jump height against phi, one panel per model, one line per kind; hard
/// ground dashed at the same colour.
pub fn height_vs_phi(best: &[BestRow]) -> GridFigure {
    let panels = [ModelName::Eq1, ModelName::Eq4]
        .into_iter()
        .map(|model| {
            let mut lines = Vec::new();
            for (i, (kind, tau)) in KINDS.into_iter().enumerate() {
                let pts: Vec<(f64, f64)> = best
                    .iter()
                    .filter(|b| is(&b.kind, &b.model, kind, model) && b.tau_s == tau)
                    .filter_map(|b| b.phi.map(|phi| (phi, 1e3 * b.jump_height_m)))
                    .collect();
                lines.push(Line {
                    label: kind_label(kind),
                    points: pts,
                    color: palette(i),
                    dashed: false,
                    markers: true,
                });
            }
            let phis: Vec<f64> = lines[0].points.iter().map(|p| p.0).collect();
            let (lo, hi) = (
                phis.first().copied().unwrap_or(0.57),
                phis.last().copied().unwrap_or(0.62),
            );
            for (i, (kind, tau)) in KINDS.into_iter().enumerate() {
                if let Some(h) = best
                    .iter()
                    .find(|b| is(&b.kind, &b.model, kind, ModelName::Hard) && b.tau_s == tau)
                {
                    let y = 1e3 * h.jump_height_m;
                    lines.push(Line {
                        label: if i == 0 {
                            "dashed: hard ground".into()
                        } else {
                            String::new()
                        },
                        points: vec![(lo, y), (hi, y)],
                        color: palette(i),
                        dashed: true,
                        markers: false,
                    });
                }
            }
            LinePanel {
                caption: format!("model {model}: height at each kind's best frequency"),
                x_desc: "packing fraction φ".into(),
                y_desc: "jump height (mm)".into(),
                lines,
                y_from_zero: true,
            }
        })
        .collect();
    GridFigure::row("Jump height vs packing fraction", panels)
}

/// Figure 2: height against forcing frequency, panels (eq1, eq4) x (single, stutter), lines
/// for `phis` and hard ground.
pub fn height_vs_freq(rows: &[SweepRow], phis: &[f64]) -> GridFigure {
    let mut panels = Vec::new();
    for model in [ModelName::Eq1, ModelName::Eq4] {
        for kind in [JumpKind::Single, JumpKind::Stutter] {
            let points = |phi: f64, height: fn(&SweepRow) -> f64| -> Vec<(f64, f64)> {
                rows.iter()
                    .filter(|r| is(&r.kind, &r.model, kind, model) && (r.phi - phi).abs() < 1e-9)
                    .map(|r| (r.freq_hz, 1e3 * height(r)))
                    .collect()
            };
            let mut lines: Vec<Line> = phis
                .iter()
                .enumerate()
                .map(|(i, &phi)| Line {
                    label: format!("φ = {phi}"),
                    points: points(phi, |r| r.jump_height_m),
                    color: palette(i),
                    dashed: false,
                    markers: false,
                })
                .collect();
            if kind == JumpKind::Stutter {
                // The stutter's jump height includes its preliminary hop; the push-off
                // (final) height is where the ground laws differ.
                for (i, &phi) in phis.iter().enumerate() {
                    lines.push(Line {
                        label: if i == 0 {
                            "dashed: final (push-off)".into()
                        } else {
                            String::new()
                        },
                        points: points(phi, |r| r.final_jump_height_m),
                        color: palette(i),
                        dashed: true,
                        markers: false,
                    });
                }
            }
            lines.push(Line {
                label: "hard ground".into(),
                points: rows
                    .iter()
                    .filter(|r| is(&r.kind, &r.model, kind, ModelName::Hard))
                    .map(|r| (r.freq_hz, 1e3 * r.jump_height_m))
                    .collect(),
                color: plotters::style::RGBColor(30, 30, 30),
                dashed: true,
                markers: false,
            });
            panels.push(LinePanel {
                caption: format!("{}, model {model}", kind_label(kind)),
                x_desc: "forcing frequency f (Hz)".into(),
                y_desc: "jump height (mm)".into(),
                lines,
                y_from_zero: true,
            });
        }
    }
    GridFigure::square("Jump height vs forcing frequency", panels)
}

/// Figure 3: the delayed stutter at [`LOW_PHI`] against its delay (at each delay's best
/// frequency), with the single jump's best height dashed; and the best frequency.
pub fn height_vs_tau(tau_best: &[BestRow], best: &[BestRow]) -> GridFigure {
    let mut heights = Vec::new();
    let mut freqs = Vec::new();
    for (i, model) in [ModelName::Eq1, ModelName::Eq4].into_iter().enumerate() {
        let mine: Vec<&BestRow> = tau_best
            .iter()
            .filter(|b| b.model == model.as_str())
            .collect();
        heights.push(Line {
            label: format!("delayed stutter, {model}"),
            points: mine
                .iter()
                .map(|b| (b.tau_s, 1e3 * b.jump_height_m))
                .collect(),
            color: palette(i),
            dashed: false,
            markers: true,
        });
        let taus: Vec<f64> = mine.iter().map(|b| b.tau_s).collect();
        if let (Some(single), Some(&t0), Some(&t1)) = (
            super::sweeps::find_best(best, JumpKind::Single, model, Some(LOW_PHI)),
            taus.first(),
            taus.last(),
        ) {
            let y = 1e3 * single.jump_height_m;
            heights.push(Line {
                label: format!("single, {model} (dashed)"),
                points: vec![(t0, y), (t1, y)],
                color: palette(i),
                dashed: true,
                markers: false,
            });
        }
        freqs.push(Line {
            label: format!("{model}"),
            points: mine.iter().map(|b| (b.tau_s, b.best_freq_hz)).collect(),
            color: palette(i),
            dashed: false,
            markers: true,
        });
    }
    delay_panels(
        format!("Delayed stutter vs delay τ at φ = {LOW_PHI}"),
        heights,
        freqs,
    )
}

/// Two panels against the delay: the height at each delay's best frequency, and that
/// frequency.
fn delay_panels(title: String, heights: Vec<Line>, freqs: Vec<Line>) -> GridFigure {
    GridFigure::row(
        title,
        vec![
            LinePanel {
                caption: "height at each delay's best frequency".into(),
                x_desc: "delay τ (s)".into(),
                y_desc: "jump height (mm)".into(),
                lines: heights,
                y_from_zero: true,
            },
            LinePanel {
                caption: "best forcing frequency".into(),
                x_desc: "delay τ (s)".into(),
                y_desc: "best frequency f (Hz)".into(),
                lines: freqs,
                y_from_zero: true,
            },
        ],
    )
}

/// The delay curve the way the rig made it: the eq4 delayed stutter at phi = 0.57 against its
/// delay, kinematic (the stroke imposed; the spring rings through the delay) beside the
/// software-in-the-loop rig with gain lowering (the controller, the 300 N drive, the encoder;
/// the lowered gain damps the ringing).
pub fn delay_curve_sil(kinematic: &[BestRow], sil: &[BestRow], sil_label: &str) -> GridFigure {
    let mut heights = Vec::new();
    let mut freqs = Vec::new();
    for (i, (rows, label)) in [(kinematic, "kinematic"), (sil, sil_label)]
        .into_iter()
        .enumerate()
    {
        heights.push(Line {
            label: label.into(),
            points: rows
                .iter()
                .map(|b| (b.tau_s, 1e3 * b.jump_height_m))
                .collect(),
            color: palette(i),
            dashed: false,
            markers: true,
        });
        freqs.push(Line {
            label: label.into(),
            points: rows.iter().map(|b| (b.tau_s, b.best_freq_hz)).collect(),
            color: palette(i),
            dashed: false,
            markers: true,
        });
    }
    delay_panels(
        format!(
            "Delayed stutter vs delay τ at φ = {LOW_PHI}, eq4: kinematic and through the SIL rig"
        ),
        heights,
        freqs,
    )
}

/// The delay of the highest jump among `rows` (each at its best frequency): (tau, height,
/// frequency).
pub fn tau_opt(rows: &[BestRow]) -> Option<(f64, f64, f64)> {
    rows.iter()
        .max_by(|a, b| a.jump_height_m.total_cmp(&b.jump_height_m))
        .map(|b| (b.tau_s, b.jump_height_m, b.best_freq_hz))
}
