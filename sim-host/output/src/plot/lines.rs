//! Line charts: one or more panels of labelled lines, side by side, under one title.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    FONT, Figure, LegendEntry, PlotResult, draw_legend_column, padded_range, stroke_pieces,
    tick_label,
};

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
        let root = root.margin(12, 8, 8, 8);
        let body = root.titled(&self.title, (FONT, 30).into_font().style(FontStyle::Bold))?;
        let (rows, cols) = grid_shape(self.panels.len());
        let areas = body.split_evenly((rows, cols));
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            draw_line_panel(area, panel)?;
        }
        Ok(())
    }
}

/// Rows and columns of the panel grid: at most three columns.
pub fn grid_shape(panels: usize) -> (usize, usize) {
    let cols = panels.clamp(1, 3);
    (panels.max(1).div_ceil(cols), cols)
}

/// Pixel size of a figure of `panels` panels of the default size.
pub fn grid_size(panels: usize) -> (u32, u32) {
    let (rows, cols) = grid_shape(panels);
    (40 + 1050 * cols as u32, 60 + 720 * rows as u32)
}

/// Width of the legend column right of each panel, pixels.
pub const PANEL_LEGEND_WIDTH: u32 = 270;

/// Draw one panel into `area`: axes, grid, lines (markers, dashes), and the legend in a
/// column at the panel's right so it never covers data.
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
    let area = area.titled(&panel.caption, (FONT, 24))?;
    let w = area.dim_in_pixel().0;
    let (plot, legend) = area.split_horizontally(w.saturating_sub(PANEL_LEGEND_WIDTH));
    let top = 12;
    let mut chart = ChartBuilder::on(&plot)
        .margin(top)
        .x_label_area_size(65)
        .y_label_area_size(95)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(&panel.x_desc)
        .y_desc(&panel.y_desc)
        .axis_desc_style((FONT, 22))
        .label_style((FONT, 18))
        .x_label_formatter(&tick_label)
        .y_label_formatter(&tick_label)
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(222, 222, 222))
        .draw()?;
    let mut entries = Vec::new();
    for line in &panel.lines {
        let style = line.color.stroke_width(3);
        if line.dashed {
            chart.draw_series(DashedLineSeries::new(
                line.points.iter().copied(),
                10,
                6,
                style,
            ))?;
        } else {
            for piece in stroke_pieces(&chart, line.points.iter().copied()) {
                chart.draw_series(LineSeries::new(piece, style))?;
            }
        }
        if line.markers {
            chart.draw_series(
                line.points
                    .iter()
                    .map(|&p| Circle::new(p, 4, line.color.filled())),
            )?;
        }
        if !line.label.is_empty() {
            entries.push(LegendEntry::line(&line.label, line.color, line.dashed));
        }
    }
    draw_legend_column(&legend, &entries, top)
}
