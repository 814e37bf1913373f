//! The figure of a search: the best stroke beside the paper's best (motor position p(t)),
//! their jumps (rod height), and the search's convergence.

use sandjumper_model::record::SeriesRow;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel};
use sandjumper_output::plot::palette;

use crate::search::HistoryRow;

/// One stroke and its jump, for the figure.
pub struct Shown<'a> {
    /// Legend label.
    pub label: String,
    /// The stroke table `(t, p)`, s and m.
    pub stroke: Vec<(f64, f64)>,
    /// The jump's series.
    pub series: &'a [SeriesRow],
}

/// The figure: p(t) and rod height for each shown stroke, and the best value per evaluation.
pub fn search_figure(
    title: String,
    shown: &[Shown<'_>],
    history: &[HistoryRow],
    objective: &str,
    unit: &str,
) -> LineFigure {
    let line = |label: &str, points: Vec<(f64, f64)>, i: usize| Line {
        label: label.to_string(),
        points,
        color: palette(i),
        dashed: i > 0,
        markers: false,
    };
    let strokes = LinePanel {
        caption: "motor stroke".into(),
        x_desc: "time t (s)".into(),
        y_desc: "motor position p (mm)".into(),
        lines: shown
            .iter()
            .enumerate()
            .map(|(i, s)| {
                line(
                    &s.label,
                    s.stroke.iter().map(|&(t, p)| (t, 1e3 * p)).collect(),
                    i,
                )
            })
            .collect(),
        y_from_zero: false,
    };
    let jumps = LinePanel {
        caption: "the jump (kinematic model)".into(),
        x_desc: "time t (s)".into(),
        y_desc: "rod height above rest (mm)".into(),
        lines: shown
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let x0 = s.series.first().map_or(0.0, |r| r.x_r);
                line(
                    &s.label,
                    s.series
                        .iter()
                        .map(|r| (r.t_s, 1e3 * (r.x_r - x0)))
                        .collect(),
                    i,
                )
            })
            .collect(),
        y_from_zero: false,
    };
    let scale = if unit == "m" { 1e3 } else { 1.0 };
    let shown_unit = if unit == "m" { "mm" } else { unit };
    let mut starts: Vec<usize> = history.iter().map(|h| h.start).collect();
    starts.dedup();
    let convergence = LinePanel {
        caption: "search".into(),
        x_desc: "evaluations".into(),
        y_desc: format!("best {objective} ({shown_unit})"),
        lines: vec![Line {
            label: "best so far".into(),
            points: history
                .iter()
                .filter(|h| h.best_so_far.is_finite())
                .map(|h| (h.evaluations as f64, scale * h.best_so_far))
                .collect(),
            color: palette(0),
            dashed: false,
            markers: false,
        }]
        .into_iter()
        .chain(starts.iter().map(|&s| {
            Line {
                label: String::new(),
                points: history
                    .iter()
                    .filter(|h| h.start == s && h.generation_best.is_finite())
                    .map(|h| (h.evaluations as f64, scale * h.generation_best))
                    .collect(),
                color: palette(3 + s),
                dashed: true,
                markers: false,
            }
        }))
        .collect(),
        y_from_zero: false,
    };
    LineFigure {
        title,
        panels: vec![strokes, jumps, convergence],
        size: sandjumper_output::plot::lines::grid_size(3),
    }
}
