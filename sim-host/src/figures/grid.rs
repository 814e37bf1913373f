//! A figure of line panels on a rows x columns grid (the plot module's [`LineFigure`] puts
//! its panels side by side; four time-series panels read better as 2 x 2).
//!
//! [`LineFigure`]: crate::plot::lines::LineFigure

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::plot::lines::{LinePanel, draw_line_panel};
use crate::plot::{FONT, Figure, PlotResult};

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
        let body = root.titled(&self.title, (FONT, 30).into_font().style(FontStyle::Bold))?;
        let areas = body.split_evenly(self.shape);
        for (panel, area) in self.panels.iter().zip(areas.iter()) {
            draw_line_panel(area, panel)?;
        }
        Ok(())
    }
}
