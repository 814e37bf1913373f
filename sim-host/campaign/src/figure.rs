//! A campaign's figures: jump height against the achieved packing fraction per kind
//! (measured by the camera beside predicted by the replay), and the paper's Fig. 2a (jump
//! height against forcing frequency per kind) made from the campaign's jumps.

use std::path::Path;

use super::records::State;
use sandjumper_output::plot::PALETTE;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::save_figure;

/// Lines for one panel: per `group` value, measured (solid) and predicted (dashed) heights
/// against `x`, sorted by x.
fn lines(
    rows: &[&super::records::ResultRow],
    x: impl Fn(&super::records::ResultRow) -> f64,
    group: impl Fn(&super::records::ResultRow) -> String,
) -> Vec<Line> {
    let mut groups: Vec<String> = rows.iter().map(|r| group(r)).collect();
    groups.sort();
    groups.dedup();
    let mut out = Vec::new();
    for (k, g) in groups.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        for (label, measured) in [("camera", true), ("replay", false)] {
            let mut pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| &group(r) == g)
                .filter_map(|r| {
                    let h = if measured {
                        r.measured_jump_height_m
                    } else {
                        r.predicted_jump_height_m
                    }?;
                    Some((x(r), 1e3 * h))
                })
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            if !pts.is_empty() {
                out.push(Line {
                    label: format!("{g}, {label}"),
                    points: pts,
                    color,
                    dashed: !measured,
                    markers: true,
                });
            }
        }
    }
    out
}

/// Write `height_vs_phi.png/.svg` and `fig2a.png/.svg` into `dir`.
pub fn write(dir: &Path, state: &State) -> Result<(), String> {
    let done: Vec<&super::records::ResultRow> =
        state.rows.values().filter(|r| r.status == "done").collect();
    let mut kinds: Vec<String> = done.iter().map(|r| r.kind.clone()).collect();
    kinds.sort();
    kinds.dedup();
    if kinds.is_empty() {
        kinds.push("(no jumps yet)".into());
    }
    let panel = |kind: &str, by_phi: bool| {
        let rows: Vec<&super::records::ResultRow> =
            done.iter().copied().filter(|r| r.kind == kind).collect();
        LinePanel {
            caption: kind.to_string(),
            x_desc: if by_phi {
                "achieved packing fraction φ".into()
            } else {
                "forcing frequency f (Hz)".into()
            },
            y_desc: "jump height (mm)".into(),
            lines: if by_phi {
                lines(&rows, |r| r.achieved_phi, |r| format!("{} Hz", r.freq_hz))
            } else {
                lines(&rows, |r| r.freq_hz, |r| format!("φ {:.3}", r.target_phi))
            },
            y_from_zero: true,
        }
    };
    for (name, by_phi, title) in [
        (
            "height_vs_phi",
            true,
            format!(
                "{}: jump height against the achieved φ (camera solid, replay dashed)",
                state.name
            ),
        ),
        (
            "fig2a",
            false,
            format!(
                "{}: jump height against frequency (the paper's Fig. 2a; camera solid, replay dashed)",
                state.name
            ),
        ),
    ] {
        let panels: Vec<LinePanel> = kinds.iter().map(|k| panel(k, by_phi)).collect();
        let fig = LineFigure {
            title,
            size: grid_size(panels.len()),
            panels,
        };
        save_figure(
            &fig,
            &dir.join(format!("{name}.png")),
            Some(&dir.join(format!("{name}.svg"))),
        )
        .map_err(|e| format!("cannot draw {name}: {e}"))?;
    }
    Ok(())
}
