//! The figure of one jump, for a lab notebook: stacked panels sharing the time axis.
//!
//! 1. Heights of motor, rod and foot relative to their rest positions (mm), the undisturbed
//!    sand surface, and the rod's apex (the jump height) marked.
//! 2. Spring force `F_s` and ground force `F_GM` (N).
//! 3. Added mass `m_a` (g), only when the added-mass law produced any.
//!
//! Every panel is shaded by ground mode (aerial / static / intruding).

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::hybrid::GroundMode;
use crate::jump::{JumpSummary, SeriesRow};

use super::{FONT, Figure, PlotResult, padded_range, palette};

/// Background colour of a ground mode.
pub fn mode_color(mode: GroundMode) -> RGBColor {
    match mode {
        GroundMode::Aerial => RGBColor(190, 220, 255),
        GroundMode::Static => RGBColor(215, 215, 215),
        GroundMode::Intruding => RGBColor(245, 215, 160),
    }
}

/// Legend name of a ground mode.
pub fn mode_label(mode: GroundMode) -> &'static str {
    match mode {
        GroundMode::Aerial => "aerial",
        GroundMode::Static => "static (held by sand)",
        GroundMode::Intruding => "intruding",
    }
}

/// Maximal time intervals `(t0, t1, mode)` over which the mode is constant.
pub fn mode_intervals(rows: &[SeriesRow]) -> Vec<(f64, f64, GroundMode)> {
    let mut out: Vec<(f64, f64, GroundMode)> = Vec::new();
    for w in rows.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        match out.last_mut() {
            Some(last) if last.2 == a.mode => last.1 = b.t_s,
            _ => out.push((a.t_s, b.t_s, a.mode)),
        }
    }
    out
}

/// The figure of one jump.
#[derive(Clone, Debug)]
pub struct JumpFigure<'a> {
    /// Title, e.g. "single jump, f = 12 Hz, model eq4, φ = 0.57".
    pub title: String,
    /// Time series (SI).
    pub rows: &'a [SeriesRow],
    /// The jump's metrics (apex, height, depth).
    pub summary: &'a JumpSummary,
}

const PANEL_LABEL_AREA: u32 = 95;

/// Picks one quantity out of a series row.
type Column = fn(&SeriesRow) -> f64;

impl JumpFigure<'_> {
    fn has_added_mass(&self) -> bool {
        self.rows.iter().any(|r| r.m_a > 0.0)
    }

    fn time_range(&self) -> (f64, f64) {
        let t0 = self.rows.first().map_or(0.0, |r| r.t_s);
        let t1 = self.rows.last().map_or(1.0, |r| r.t_s);
        if t1 > t0 { (t0, t1) } else { (t0, t0 + 1.0) }
    }

    /// Draw the mode shading of `rows` on a chart; labels the modes in the legend if asked.
    fn shade<DB: DrawingBackend>(
        &self,
        chart: &mut ChartContext<
            '_,
            DB,
            Cartesian2d<
                plotters::coord::types::RangedCoordf64,
                plotters::coord::types::RangedCoordf64,
            >,
        >,
        (y0, y1): (f64, f64),
        legend: bool,
    ) -> PlotResult<()> {
        let intervals = mode_intervals(self.rows);
        for mode in [
            GroundMode::Intruding,
            GroundMode::Static,
            GroundMode::Aerial,
        ] {
            let color = mode_color(mode);
            let rects: Vec<_> = intervals
                .iter()
                .filter(|iv| iv.2 == mode)
                .map(|&(a, b, _)| Rectangle::new([(a, y0), (b, y1)], color.filled()))
                .collect();
            if rects.is_empty() {
                continue;
            }
            let drawn = chart.draw_series(rects)?;
            if legend {
                drawn.label(mode_label(mode)).legend(move |(x, y)| {
                    Rectangle::new([(x, y - 7), (x + 22, y + 7)], color.filled())
                });
            }
        }
        Ok(())
    }

    fn draw_heights<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        show_x: bool,
    ) -> PlotResult<()> {
        let Some(first) = self.rows.first() else {
            return Ok(());
        };
        let (xm0, xr0, xf0) = (first.x_m, first.x_r, first.x_f);
        let surface_mm = -1e3 * xf0;
        let show_surface = surface_mm > 1e-3;
        let ys = self
            .rows
            .iter()
            .flat_map(|r| [r.x_m - xm0, r.x_r - xr0, r.x_f - xf0].map(|v| 1e3 * v))
            .chain(show_surface.then_some(surface_mm));
        let (y0, y1) = padded_range(ys, 0.08);
        let (t0, t1) = self.time_range();
        let mut chart = ChartBuilder::on(area)
            .margin_right(25)
            .margin_top(10)
            .x_label_area_size(if show_x { 60 } else { 0 })
            .y_label_area_size(PANEL_LABEL_AREA)
            .build_cartesian_2d(t0..t1, y0..y1)?;
        self.shade(&mut chart, (y0, y1), true)?;
        let mut mesh = chart.configure_mesh();
        mesh.y_desc("height above rest (mm)")
            .axis_desc_style((FONT, 22))
            .label_style((FONT, 18))
            .light_line_style(TRANSPARENT)
            .bold_line_style(BLACK.mix(0.12));
        if show_x {
            mesh.x_desc("time t (s)");
        }
        mesh.draw()?;
        if show_surface {
            let grey = RGBColor(110, 90, 60);
            chart
                .draw_series(DashedLineSeries::new(
                    [(t0, surface_mm), (t1, surface_mm)],
                    10,
                    6,
                    grey.stroke_width(2),
                ))?
                .label("sand surface (foot scale)")
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 22, y)], grey.stroke_width(2))
                });
        }
        let traces: [(&str, RGBColor, Column, f64); 3] = [
            ("motor x_m", palette(0), |r| r.x_m, xm0),
            ("rod x_r", palette(3), |r| r.x_r, xr0),
            ("foot x_f", palette(2), |r| r.x_f, xf0),
        ];
        for (label, color, get, origin) in traces {
            chart
                .draw_series(LineSeries::new(
                    self.rows.iter().map(|r| (r.t_s, 1e3 * (get(r) - origin))),
                    color.stroke_width(3),
                ))?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
                });
        }
        let s = self.summary;
        let apex = (s.apex_time_s, 1e3 * s.jump_height_m);
        let red = palette(3);
        chart.draw_series([Circle::new(apex, 7, red.stroke_width(3))])?;
        let text = format!("jump height {:.1} mm", 1e3 * s.jump_height_m);
        let style = TextStyle::from((FONT, 20).into_font()).color(&BLACK);
        // Put the annotation left of the apex if the apex is in the right part of the plot.
        let right_side = (apex.0 - t0) / (t1 - t0) > 0.6;
        let pos = chart.backend_coord(&apex);
        let (w, _) = area.estimate_text_size(&text, &style)?;
        let x = if right_side {
            pos.0 - w as i32 - 14
        } else {
            pos.0 + 14
        };
        let (ox, oy) = area.get_base_pixel();
        area.draw(&Text::new(text, (x - ox, pos.1 - oy - 26), style))?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, 18))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()?;
        Ok(())
    }

    fn draw_forces<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        show_x: bool,
    ) -> PlotResult<()> {
        let ys = self.rows.iter().flat_map(|r| [r.f_s, r.f_gm]).chain([0.0]);
        let (y0, y1) = padded_range(ys, 0.08);
        let (t0, t1) = self.time_range();
        let mut chart = ChartBuilder::on(area)
            .margin_right(25)
            .margin_top(10)
            .x_label_area_size(if show_x { 60 } else { 0 })
            .y_label_area_size(PANEL_LABEL_AREA)
            .build_cartesian_2d(t0..t1, y0..y1)?;
        self.shade(&mut chart, (y0, y1), false)?;
        let mut mesh = chart.configure_mesh();
        mesh.y_desc("force (N)")
            .axis_desc_style((FONT, 22))
            .label_style((FONT, 18))
            .light_line_style(TRANSPARENT)
            .bold_line_style(BLACK.mix(0.12));
        if show_x {
            mesh.x_desc("time t (s)");
        }
        mesh.draw()?;
        let traces: [(&str, RGBColor, Column); 2] = [
            ("spring F_s (> 0 compressed)", palette(4), |r| r.f_s),
            ("ground F_GM on foot", palette(5), |r| r.f_gm),
        ];
        for (label, color, get) in traces {
            chart
                .draw_series(LineSeries::new(
                    self.rows.iter().map(|r| (r.t_s, get(r))),
                    color.stroke_width(3),
                ))?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FONT, 18))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()?;
        Ok(())
    }

    fn draw_added_mass<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> PlotResult<()> {
        let ys = self.rows.iter().map(|r| 1e3 * r.m_a).chain([0.0]);
        let (_, y1) = padded_range(ys, 0.08);
        let y0 = 0.0;
        let (t0, t1) = self.time_range();
        let mut chart = ChartBuilder::on(area)
            .margin_right(25)
            .margin_top(10)
            .x_label_area_size(60)
            .y_label_area_size(PANEL_LABEL_AREA)
            .build_cartesian_2d(t0..t1, y0..y1)?;
        self.shade(&mut chart, (y0, y1), false)?;
        chart
            .configure_mesh()
            .x_desc("time t (s)")
            .y_desc("added mass m_a (g)")
            .axis_desc_style((FONT, 22))
            .label_style((FONT, 18))
            .light_line_style(TRANSPARENT)
            .bold_line_style(BLACK.mix(0.12))
            .draw()?;
        let color = palette(1);
        chart.draw_series(LineSeries::new(
            self.rows.iter().map(|r| (r.t_s, 1e3 * r.m_a)),
            color.stroke_width(3),
        ))?;
        Ok(())
    }

    fn subtitle(&self) -> String {
        let s = self.summary;
        let mut parts = vec![format!("jump height {:.1} mm", 1e3 * s.jump_height_m)];
        if (s.final_jump_height_m - s.jump_height_m).abs() > 1e-7 {
            parts.push(format!(
                "final (push-off) {:.1} mm",
                1e3 * s.final_jump_height_m
            ));
        }
        parts.push(format!("max depth {:.1} mm", 1e3 * s.max_depth_m));
        if s.peak_added_mass_kg > 0.0 {
            parts.push(format!(
                "peak added mass {:.0} g",
                1e3 * s.peak_added_mass_kg
            ));
        }
        parts.push(format!("peak motor force {:.0} N", s.peak_motor_force_n));
        parts.join("   ·   ")
    }
}

impl Figure for JumpFigure<'_> {
    fn size(&self) -> (u32, u32) {
        if self.has_added_mass() {
            (1400, 1150)
        } else {
            (1400, 950)
        }
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult<()> {
        let body = root.titled(&self.title, (FONT, 32).into_font().style(FontStyle::Bold))?;
        let (sub, body) = body.split_vertically(36);
        sub.draw(&Text::new(
            self.subtitle(),
            (PANEL_LABEL_AREA as i32 + 10, 4),
            (FONT, 21).into_font().color(&RGBColor(60, 60, 60)),
        ))?;
        let h = body.dim_in_pixel().1;
        if self.has_added_mass() {
            let (top, rest) = body.split_vertically(h * 45 / 100);
            let (mid, bottom) = rest.split_vertically(h * 30 / 100);
            self.draw_heights(&top, false)?;
            self.draw_forces(&mid, false)?;
            self.draw_added_mass(&bottom)?;
        } else {
            let (top, bottom) = body.split_vertically(h * 58 / 100);
            self.draw_heights(&top, false)?;
            self.draw_forces(&bottom, true)?;
        }
        Ok(())
    }
}
