//! DEM figures: a snapshot of the grains coloured by speed (PNG and SVG).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::grains::FREE;
use super::render::SideCamera;
use super::world::World;
use crate::error::DemError;
use sandjumper_output::plot::{FONT, Figure, PlotResult, save_figure};

/// Grains in a window, drawn as circles coloured by speed.
pub struct SnapshotFigure {
    /// Title.
    pub title: String,
    /// `(x, y, r, speed)` of free grains, m and m/s.
    pub grains: Vec<(f64, f64, f64, f64)>,
    /// `(x, y, r)` of intruder grains, m.
    pub intruder: Vec<(f64, f64, f64)>,
    /// Window: left, right, bottom, top, m.
    pub window: (f64, f64, f64, f64),
    /// Speed at the top of the colour scale, m/s.
    pub v_max_m_s: f64,
}

impl Figure for SnapshotFigure {
    fn size(&self) -> (u32, u32) {
        let (l, r, b, t) = self.window;
        let aspect = ((t - b) / (r - l)).clamp(0.2, 3.0);
        (1000, (900.0 * aspect) as u32 + 100)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult<()> {
        let (l, r, b, t) = self.window;
        let mut chart = ChartBuilder::on(root)
            .margin(12)
            .caption(&self.title, (FONT, 20))
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(1e3 * l..1e3 * r, 1e3 * b..1e3 * t)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (mm)")
            .y_desc("height (mm)")
            .label_style((FONT, 14))
            .draw()?;
        let px_per_m = 1000.0 / (r - l) * 0.9;
        chart.draw_series(self.grains.iter().map(|&(x, y, rad, s)| {
            Circle::new(
                (1e3 * x, 1e3 * y),
                (rad * px_per_m).max(1.0),
                sandjumper_flow::figure::colour(s / self.v_max_m_s.max(1e-12)).filled(),
            )
        }))?;
        chart.draw_series(self.intruder.iter().map(|&(x, y, rad)| {
            Circle::new((1e3 * x, 1e3 * y), (rad * px_per_m).max(1.0), RED.filled())
        }))?;
        Ok(())
    }
}

/// Save a snapshot of the window `cam` sees, speeds up to `v_max`.
pub fn save_snapshot(
    w: &World,
    cam: &SideCamera,
    v_max: f64,
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), DemError> {
    let l = cam.left_m;
    let r = l + f64::from(cam.width_px) * cam.m_per_px;
    let t = cam.top_m;
    let b = t - f64::from(cam.height_px) * cam.m_per_px;
    let g = &w.g;
    let inside = |i: usize| g.x[i] >= l && g.x[i] <= r && g.y[i] >= b && g.y[i] <= t;
    let fig = SnapshotFigure {
        title: title.into(),
        grains: (0..g.len())
            .filter(|&i| g.kind[i] == FREE && inside(i))
            .map(|i| (g.x[i], g.y[i], g.radius[i], w.u.x[i].hypot(w.u.y[i])))
            .collect(),
        intruder: (0..g.len())
            .filter(|&i| g.kind[i] != FREE && inside(i))
            .map(|i| (g.x[i], g.y[i], g.radius[i]))
            .collect(),
        window: (l, r, b, t),
        v_max_m_s: v_max,
    };
    save_figure(&fig, png, Some(svg))?;
    Ok(())
}
