//! Line charts: one or more panels of labelled lines, side by side, under one title.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{FONT, Figure, PlotResult, padded_range};

/// One line of a chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// Legend text (empty: not in the legend).
    pub label: String,
    /// Points in data units, drawn in the given order.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Dashed instead of solid.
    pub dashed: bool,
    /// Draw a marker at every point (for coarse sweeps).
    pub markers: bool,
}

/// One panel: axes with labels (units in the text) and its lines.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct LinePanel {
    /// Caption above the panel (may be empty).
    pub caption: String,
    /// x-axis label with unit, e.g. "forcing frequency f (Hz)".
    pub x_desc: String,
    /// y-axis label with unit.
    pub y_desc: String,
    /// The lines.
    pub lines: Vec<Line>,
    /// Start the y axis at zero when all values are positive (heights, forces).
    pub y_from_zero: bool,
}

/// A figure of panels side by side under one title.
#[derive(Clone, Debug, PartialEq)]
pub struct LineFigure {
    /// Title over all panels.
    pub title: String,
    /// Panels, left to right.
    pub panels: Vec<LinePanel>,
    /// Pixel size.
    pub size: (u32, u32),
}

impl Figure for LineFigure {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult<()> {
        let body = root.titled(&self.title, (FONT, 30).into_font().style(FontStyle::Bold))?;
        let areas = body.split_evenly((1, self.panels.len().max(1)));
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            draw_line_panel(area, panel)?;
        }
        Ok(())
    }
}

/// Draw one panel into `area`: axes, grid, lines (markers, dashes) and a legend.
pub fn draw_line_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &LinePanel,
) -> PlotResult<()> {
    let xs = panel
        .lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.0));
    let (x0, x1) = padded_range(xs, 0.03);
    let ys: Vec<f64> = panel
        .lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.1))
        .collect();
    let (mut y0, y1) = padded_range(ys.iter().copied(), 0.08);
    if panel.y_from_zero && ys.iter().all(|&y| y >= 0.0) {
        y0 = 0.0;
    }
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.caption, (FONT, 24))
        .margin(12)
        .x_label_area_size(60)
        .y_label_area_size(85)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(&panel.x_desc)
        .y_desc(&panel.y_desc)
        .axis_desc_style((FONT, 22))
        .label_style((FONT, 18))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()?;
    let mut any_label = false;
    for line in &panel.lines {
        let color = line.color;
        let style = color.stroke_width(3);
        let annotated = if line.dashed {
            chart.draw_series(DashedLineSeries::new(
                line.points.iter().copied(),
                10,
                6,
                style,
            ))?
        } else {
            chart.draw_series(LineSeries::new(line.points.iter().copied(), style))?
        };
        if !line.label.is_empty() {
            any_label = true;
            let dashed = line.dashed;
            annotated.label(&line.label).legend(move |(x, y)| {
                if dashed {
                    PathElement::new(vec![(x, y), (x + 8, y)], color.stroke_width(3))
                } else {
                    PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
                }
            });
        }
        if line.markers {
            chart.draw_series(
                line.points
                    .iter()
                    .map(|&p| Circle::new(p, 4, color.filled())),
            )?;
        }
    }
    if any_label {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FONT, 18))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()?;
    }
    Ok(())
}
