//! A figure of line panels on a chosen rows x columns grid (the plot module's [`LineFigure`]
//! picks its own grid, at most three columns; four panels read better as 2 x 2), drawn with
//! the plot module's [`draw_line_panel`].
//!
//! [`LineFigure`]: sandjumper_output::plot::lines::LineFigure
//! [`draw_line_panel`]: sandjumper_output::plot::lines::draw_line_panel

use plotters::coord::Shift;
use plotters::prelude::*;

use sandjumper_output::plot::lines::{LinePanel, draw_line_panel, grid_size};
use sandjumper_output::plot::{FONT, Figure, PlotResult};

/// Panels on a grid, filled row by row, under one title.
#[derive(Clone, Debug, PartialEq)]
pub struct GridFigure {
    /// Title over all panels.
    pub title: String,
    /// Grid shape (rows, columns).
    pub shape: (usize, usize),
    /// Panels, row by row.
    pub panels: Vec<LinePanel>,
    /// Pixel size.
    pub size: (u32, u32),
}

impl Figure for GridFigure {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult<()> {
        // A top margin keeps the title's ascenders inside the picture.
        let body = root
            .margin(14, 0, 0, 0)
            .titled(&self.title, (FONT, 30).into_font().style(FontStyle::Bold))?;
        let areas = body.split_evenly(self.shape);
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            draw_line_panel(area, panel)?;
        }
        Ok(())
    }
}

impl GridFigure {
    /// Panels side by side in one row, each of the plot module's default size.
    pub fn row(title: impl Into<String>, panels: Vec<LinePanel>) -> Self {
        let n = panels.len().max(1);
        Self {
            title: title.into(),
            shape: (1, n),
            size: grid_size(n),
            panels,
        }
    }

    /// Four panels on a 2 x 2 grid.
    pub fn square(title: impl Into<String>, panels: Vec<LinePanel>) -> Self {
        let (w, _) = grid_size(2);
        let (_, h) = grid_size(4);
        Self {
            title: title.into(),
            shape: (2, 2),
            size: (w, h + 30),
            panels,
        }
    }
}
