//! `track.png/.svg`: the rod height measured frame by frame with the fitted apex parabola,
//! and a thumbnail of the ball in the highest frame with its measured centre.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::frame::GrayFrame;
use super::track::{TrackResult, TrackedFrame};
use crate::ball::FixStatus;
use sandjumper_output::plot::lines::{Line, LinePanel, draw_line_panel};
use sandjumper_output::plot::{FONT, Figure, PlotResult, palette};

/// Cells of the thumbnail along its longer side.
const THUMB_CELLS: u32 = 64;

/// A thumbnail: grey cells (0..1) around the ball, and the centre in cell units.
#[derive(Clone, Debug, PartialEq)]
pub struct Thumbnail {
    /// Cells per row.
    pub cols: u32,
    /// Rows.
    pub rows: u32,
    /// Grey levels, row-major, 0 (black) to 1 (white).
    pub cells: Vec<f64>,
    /// Measured centre, in cells (x, y).
    pub centre: (f64, f64),
    /// Frame number shown.
    pub frame: u64,
}

/// The thumbnail of `frame` around `(x, y)` px, `half` px each way.
pub fn thumbnail(frame: &GrayFrame, number: u64, x: f64, y: f64, half: f64) -> Thumbnail {
    let x0 = (x - half).floor().max(0.0) as u32;
    let y0 = (y - half).floor().max(0.0) as u32;
    let x1 = ((x + half).ceil() as u32).min(frame.width());
    let y1 = ((y + half).ceil() as u32).min(frame.height());
    let step = ((x1 - x0).max(y1 - y0)).div_ceil(THUMB_CELLS).max(1);
    let (cols, rows) = ((x1 - x0) / step, (y1 - y0) / step);
    let max = frame.depth().max_value() as f64;
    let mut cells = Vec::with_capacity((cols * rows) as usize);
    for r in 0..rows {
        for c in 0..cols {
            let mut sum = 0.0;
            for dy in 0..step {
                for dx in 0..step {
                    sum += f64::from(frame.get(x0 + c * step + dx, y0 + r * step + dy));
                }
            }
            cells.push(sum / f64::from(step * step) / max);
        }
    }
    Thumbnail {
        cols,
        rows,
        cells,
        centre: (
            (x - f64::from(x0)) / f64::from(step),
            (y - f64::from(y0)) / f64::from(step),
        ),
        frame: number,
    }
}

/// The figure.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackFigure {
    /// Title.
    pub title: String,
    /// Height panel.
    pub heights: LinePanel,
    /// The ball at the top.
    pub thumbnail: Option<Thumbnail>,
}

/// The figure of a tracking result.
pub fn figure(title: String, result: &TrackResult, thumbnail: Option<Thumbnail>) -> TrackFigure {
    let ok: Vec<&TrackedFrame> = result
        .frames
        .iter()
        .filter(|f| f.status == FixStatus::Ok)
        .collect();
    let mut lines = vec![Line {
        label: "measured (each frame)".into(),
        points: ok.iter().map(|f| (f.t_s, 1e3 * f.rod_height_m)).collect(),
        color: palette(0),
        dashed: false,
        markers: true,
    }];
    let a = &result.apex;
    if let Some(accel) = a.fitted_accel_m_s2 {
        let n = 40;
        let half = 0.025;
        lines.push(Line {
            label: format!(
                "parabola: apex {:.2} mm (a = {accel:.2} m/s²)",
                1e3 * a.jump_height_m
            ),
            points: (0..=n)
                .map(|i| {
                    let t = a.apex_time_s - half + 2.0 * half * f64::from(i) / f64::from(n);
                    let dt = t - a.apex_time_s;
                    (t, 1e3 * (a.jump_height_m + 0.5 * accel * dt * dt))
                })
                .collect(),
            color: palette(1),
            dashed: false,
            markers: false,
        });
    }
    let flagged: Vec<(f64, f64)> = result
        .frames
        .iter()
        .filter(|f| f.status != FixStatus::Ok)
        .map(|f| (f.t_s, 0.0))
        .collect();
    if !flagged.is_empty() {
        lines.push(Line {
            label: format!("flagged frames ({}), drawn at 0", flagged.len()),
            points: flagged,
            color: palette(3),
            dashed: false,
            markers: true,
        });
    }
    TrackFigure {
        title,
        heights: LinePanel {
            caption: "rod height from the camera".into(),
            x_desc: "time (s)".into(),
            y_desc: "rod height above rest (mm)".into(),
            lines,
            y_from_zero: false,
        },
        thumbnail,
    }
}

impl Figure for TrackFigure {
    fn size(&self) -> (u32, u32) {
        (1700, 780)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult<()> {
        let body = root
            .margin(14, 8, 8, 8)
            .titled(&self.title, (FONT, 28).into_font().style(FontStyle::Bold))?;
        let (left, right) = body.split_horizontally(1180);
        draw_line_panel(&left, &self.heights)?;
        let Some(t) = &self.thumbnail else {
            return Ok(());
        };
        let mut chart = ChartBuilder::on(&right.margin(30, 30, 20, 20))
            .caption(
                format!("ball in frame {} (+: measured centre)", t.frame),
                (FONT, 22),
            )
            .build_cartesian_2d(0.0..f64::from(t.cols), f64::from(t.rows)..0.0)?;
        chart.draw_series((0..t.rows).flat_map(|r| {
            (0..t.cols).map(move |c| {
                let g = (t.cells[(r * t.cols + c) as usize].clamp(0.0, 1.0) * 255.0) as u8;
                Rectangle::new(
                    [
                        (f64::from(c), f64::from(r)),
                        (f64::from(c + 1), f64::from(r + 1)),
                    ],
                    RGBColor(g, g, g).filled(),
                )
            })
        }))?;
        let (cx, cy) = t.centre;
        let arm = 0.08 * f64::from(t.cols.max(t.rows));
        for seg in [
            [(cx - arm, cy), (cx + arm, cy)],
            [(cx, cy - arm), (cx, cy + arm)],
        ] {
            chart.draw_series(std::iter::once(PathElement::new(
                seg.to_vec(),
                RED.stroke_width(3),
            )))?;
        }
        Ok(())
    }
}
