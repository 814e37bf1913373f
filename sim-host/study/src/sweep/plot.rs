//! Sweep figures: jump height against forcing frequency (one line per packing fraction) and,
//! when the delay varies, against the delay of the delayed stutter.

use plotters::style::RGBColor;

use super::SweepRow;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::palette;

/// Most lines a height-vs-delay panel shows one per (phi, frequency); beyond, one per phi at
/// its best frequency.
const MAX_TAU_LINES: usize = 8;

fn distinct<T: PartialEq + Clone>(items: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut out: Vec<T> = Vec::new();
    for x in items {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

fn kind_title(kind: &str) -> &str {
    match kind {
        "single" => "single jump",
        "stutter" => "stutter jump",
        "delayed" => "delayed stutter",
        other => other,
    }
}

fn is_stutter(kind: &str) -> bool {
    kind == "stutter" || kind == "delayed"
}

/// Push the jump-height line of `pts` (x from `x`, y in mm, colour `i`) and, for stutters,
/// the final (push-off) height of the same points dashed.
fn push_height_lines(
    lines: &mut Vec<Line>,
    i: usize,
    label: String,
    pts: &[&SweepRow],
    x: fn(&SweepRow) -> f64,
    with_final: bool,
) {
    lines.push(Line {
        label,
        points: pts.iter().map(|r| (x(r), 1e3 * r.jump_height_m)).collect(),
        color: palette(i),
        dashed: false,
        markers: true,
    });
    if with_final {
        lines.push(Line {
            label: String::new(),
            points: pts
                .iter()
                .map(|r| (x(r), 1e3 * r.final_jump_height_m))
                .collect(),
            color: palette(i),
            dashed: true,
            markers: false,
        });
    }
}

/// A legend-only entry explaining the dashed lines (no points).
fn final_height_key() -> Line {
    Line {
        label: "final (push-off) height".into(),
        points: Vec::new(),
        color: RGBColor(110, 110, 110),
        dashed: true,
        markers: false,
    }
}

/// Jump height (mm) vs forcing frequency: one panel per (kind, model), one line per phi
/// (and per tau when it varies); stutter panels add the final (push-off) height dashed.
pub fn height_vs_freq(rows: &[SweepRow], title: &str) -> LineFigure {
    let panels_keys = distinct(rows.iter().map(|r| (r.kind.clone(), r.model.clone())));
    let panels = panels_keys
        .iter()
        .map(|(kind, model)| {
            let mine: Vec<&SweepRow> = rows
                .iter()
                .filter(|r| &r.kind == kind && &r.model == model)
                .collect();
            let taus = distinct(mine.iter().map(|r| r.tau_s.to_bits()));
            let lines_keys = distinct(mine.iter().map(|r| (r.phi.to_bits(), r.tau_s.to_bits())));
            let mut lines = Vec::new();
            for (i, &(phi_b, tau_b)) in lines_keys.iter().enumerate() {
                let (phi, tau) = (f64::from_bits(phi_b), f64::from_bits(tau_b));
                let pts: Vec<&SweepRow> = mine
                    .iter()
                    .copied()
                    .filter(|r| r.phi.to_bits() == phi_b && r.tau_s.to_bits() == tau_b)
                    .collect();
                let label = if taus.len() > 1 {
                    format!("φ = {phi}, τ = {tau} s")
                } else {
                    format!("φ = {phi}")
                };
                push_height_lines(&mut lines, i, label, &pts, |r| r.freq_hz, is_stutter(kind));
            }
            if is_stutter(kind) {
                lines.push(final_height_key());
            }
            let tau_note = if kind == "delayed" && taus.len() == 1 {
                format!(", τ = {} s", f64::from_bits(taus[0]))
            } else {
                String::new()
            };
            LinePanel {
                caption: format!("{}, model {model}{tau_note}", kind_title(kind)),
                x_desc: "forcing frequency f (Hz)".into(),
                y_desc: "jump height (mm)".into(),
                lines,
                y_from_zero: true,
            }
        })
        .collect::<Vec<_>>();
    LineFigure {
        title: title.into(),
        size: grid_size(panels.len()),
        panels,
    }
}

/// Jump height (mm) vs delay tau of the delayed stutter, one panel per model, or `None` if
/// no delayed stutter with more than one delay was swept.
pub fn height_vs_tau(rows: &[SweepRow], title: &str) -> Option<LineFigure> {
    let delayed: Vec<&SweepRow> = rows.iter().filter(|r| r.kind == "delayed").collect();
    if distinct(delayed.iter().map(|r| r.tau_s.to_bits())).len() < 2 {
        return None;
    }
    let models = distinct(delayed.iter().map(|r| r.model.clone()));
    let panels = models
        .iter()
        .map(|model| {
            let mine: Vec<&SweepRow> = delayed
                .iter()
                .copied()
                .filter(|r| &r.model == model)
                .collect();
            let keys = distinct(mine.iter().map(|r| (r.phi.to_bits(), r.freq_hz.to_bits())));
            let mut lines = Vec::new();
            let best_of = keys.len() > MAX_TAU_LINES;
            if best_of {
                // One line per phi: the best height over the swept frequencies at each delay.
                for (i, phi_b) in distinct(mine.iter().map(|r| r.phi.to_bits()))
                    .into_iter()
                    .enumerate()
                {
                    let taus = distinct(
                        mine.iter()
                            .filter(|r| r.phi.to_bits() == phi_b)
                            .map(|r| r.tau_s.to_bits()),
                    );
                    let points = taus
                        .into_iter()
                        .map(|tau_b| {
                            let best = mine
                                .iter()
                                .filter(|r| r.phi.to_bits() == phi_b && r.tau_s.to_bits() == tau_b)
                                .map(|r| r.jump_height_m)
                                .fold(f64::NEG_INFINITY, f64::max);
                            (f64::from_bits(tau_b), 1e3 * best)
                        })
                        .collect();
                    lines.push(Line {
                        label: format!("φ = {}, best f", f64::from_bits(phi_b)),
                        points,
                        color: palette(i),
                        dashed: false,
                        markers: true,
                    });
                }
            } else {
                for (i, &(phi_b, f_b)) in keys.iter().enumerate() {
                    let pts: Vec<&SweepRow> = mine
                        .iter()
                        .copied()
                        .filter(|r| r.phi.to_bits() == phi_b && r.freq_hz.to_bits() == f_b)
                        .collect();
                    let (phi, f) = (f64::from_bits(phi_b), f64::from_bits(f_b));
                    let label = format!("φ = {phi}, f = {f} Hz");
                    push_height_lines(&mut lines, i, label, &pts, |r| r.tau_s, true);
                }
                lines.push(final_height_key());
            }
            LinePanel {
                caption: format!("delayed stutter, model {model}"),
                x_desc: "delay τ (s)".into(),
                y_desc: "jump height (mm)".into(),
                lines,
                y_from_zero: true,
            }
        })
        .collect::<Vec<_>>();
    Some(LineFigure {
        title: title.into(),
        size: grid_size(panels.len()),
        panels,
    })
}
