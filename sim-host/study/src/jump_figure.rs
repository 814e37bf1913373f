//! The figure of one jump, for a lab notebook: stacked panels sharing the time axis.
//!
//! 1. Heights of motor, rod and foot relative to their rest positions (mm), the undisturbed
//!    sand surface seen from the foot's rest position, and the rod's apex (the jump height).
//! 2. Spring force `F_s` and ground force `F_GM` (N).
//! 3. Added mass `m_a` (g), only when the added-mass law produced any.
//!
//! Every panel is shaded by ground mode (aerial / static / intruding); legends sit in a
//! column right of the panels so they never cover data.

use plotters::coord::Shift;
use plotters::prelude::*;

use sandjumper_model::hybrid::GroundMode;
use sandjumper_model::record::{JumpSummary, SeriesRow};

use sandjumper_output::plot::{
    FONT, Figure, LegendEntry, PlotResult, XyChart, draw_legend_column, padded_range, palette,
    stroke_pieces, tick_label,
};

/// Background colour of a ground mode.
pub fn mode_color(mode: GroundMode) -> RGBColor {
    match mode {
        GroundMode::Aerial => RGBColor(214, 232, 255),
        GroundMode::Static => RGBColor(236, 236, 236),
        GroundMode::Intruding => RGBColor(250, 222, 170),
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

/// Width of the y-label area of every panel, pixels.
const Y_LABEL_AREA: u32 = 100;
/// Width of the legend column right of the panels, pixels.
const LEGEND_WIDTH: u32 = 290;
/// Space above each panel's plotting area, pixels.
const PANEL_TOP: u32 = 12;

/// Picks one quantity out of a series row.
type Column = fn(&SeriesRow) -> f64;

/// A chart with time on x and one quantity on y.
type TimeChart<'a, DB> = XyChart<'a, DB>;

/// What one panel shows.
struct Panel<'a> {
    /// y-axis label with unit.
    y_desc: &'a str,
    /// The lines.
    traces: &'a [Trace],
    /// Values the y range must include besides the traces.
    extra_y: &'a [f64],
    /// Draw the time axis labels (bottom panel).
    show_x: bool,
    /// Legend entries after the traces'.
    extra_legend: &'a [LegendEntry],
}

/// A line of a panel: legend text, colour, the quantity, its origin, its scale to plot units.
struct Trace {
    label: &'static str,
    color: RGBColor,
    column: Column,
    origin: f64,
    scale: f64,
}

impl JumpFigure<'_> {
    fn has_added_mass(&self) -> bool {
        self.rows.iter().any(|r| r.m_a > 0.0)
    }

    fn time_range(&self) -> (f64, f64) {
        let t0 = self.rows.first().map_or(0.0, |r| r.t_s);
        let t1 = self.rows.last().map_or(1.0, |r| r.t_s);
        if t1 > t0 { (t0, t1) } else { (t0, t0 + 1.0) }
    }

    fn modes_present(&self) -> Vec<GroundMode> {
        [
            GroundMode::Aerial,
            GroundMode::Static,
            GroundMode::Intruding,
        ]
        .into_iter()
        .filter(|m| self.rows.iter().any(|r| r.mode == *m))
        .collect()
    }

    /// A panel over the run's time span: mode shading, grid, axis labels, the traces, and the
    /// legend (traces, then `extra` entries) in the column `legend`.
    fn panel<'a, DB: DrawingBackend>(
        &self,
        area: &'a DrawingArea<DB, Shift>,
        legend: &DrawingArea<DB, Shift>,
        spec: &Panel<'_>,
    ) -> PlotResult<TimeChart<'a, DB>> {
        let Panel {
            y_desc,
            traces,
            extra_y,
            show_x,
            extra_legend: extra,
        } = *spec;
        let ys = traces
            .iter()
            .flat_map(|tr| {
                self.rows
                    .iter()
                    .map(move |r| tr.scale * ((tr.column)(r) - tr.origin))
            })
            .chain(extra_y.iter().copied());
        let (y0, y1) = padded_range(ys, 0.08);
        let (t0, t1) = self.time_range();
        let mut chart = ChartBuilder::on(area)
            .margin_top(PANEL_TOP)
            .margin_left(8)
            .x_label_area_size(if show_x { 65 } else { 0 })
            .y_label_area_size(Y_LABEL_AREA)
            .build_cartesian_2d(t0..t1, y0..y1)?;
        for (a, b, mode) in mode_intervals(self.rows) {
            chart.draw_series([Rectangle::new(
                [(a, y0), (b, y1)],
                mode_color(mode).filled(),
            )])?;
        }
        let mut mesh = chart.configure_mesh();
        mesh.y_desc(y_desc)
            .axis_desc_style((FONT, 22))
            .label_style((FONT, 18))
            .x_label_formatter(&tick_label)
            .y_label_formatter(&tick_label)
            .light_line_style(TRANSPARENT)
            .bold_line_style(BLACK.mix(0.1));
        if show_x {
            mesh.x_desc("time t (s)");
        }
        mesh.draw()?;
        if y0 < 0.0 && y1 > 0.0 {
            chart.draw_series(LineSeries::new(
                [(t0, 0.0), (t1, 0.0)],
                BLACK.mix(0.35).stroke_width(1),
            ))?;
        }
        let mut entries = Vec::new();
        for tr in traces {
            let points = self
                .rows
                .iter()
                .map(|r| (r.t_s, tr.scale * ((tr.column)(r) - tr.origin)));
            for piece in stroke_pieces(&chart, points) {
                chart.draw_series(LineSeries::new(piece, tr.color.stroke_width(3)))?;
            }
            entries.push(LegendEntry::line(tr.label, tr.color, false));
        }
        entries.extend_from_slice(extra);
        draw_legend_column(legend, &entries, PANEL_TOP as i32)?;
        Ok(chart)
    }

    fn draw_heights<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        legend: &DrawingArea<DB, Shift>,
        show_x: bool,
    ) -> PlotResult<()> {
        let Some(first) = self.rows.first() else {
            return Ok(());
        };
        let surface_mm = -1e3 * first.x_f;
        let show_surface = surface_mm > 1e-3;
        let brown = RGBColor(120, 95, 60);
        let mut extra = Vec::new();
        if show_surface {
            extra.push(LegendEntry::line(
                "undisturbed surface (foot scale)",
                brown,
                true,
            ));
        }
        extra.push(LegendEntry::line("", WHITE, false));
        extra.extend(
            self.modes_present()
                .into_iter()
                .map(|m| LegendEntry::patch(mode_label(m), mode_color(m))),
        );
        let traces = [
            Trace {
                label: "motor x_m",
                color: palette(0),
                column: |r| r.x_m,
                origin: first.x_m,
                scale: 1e3,
            },
            Trace {
                label: "rod x_r",
                color: palette(3),
                column: |r| r.x_r,
                origin: first.x_r,
                scale: 1e3,
            },
            Trace {
                label: "foot x_f",
                color: palette(2),
                column: |r| r.x_f,
                origin: first.x_f,
                scale: 1e3,
            },
        ];
        let surface: &[f64] = if show_surface { &[surface_mm] } else { &[] };
        let spec = Panel {
            y_desc: "height above rest (mm)",
            traces: &traces,
            extra_y: surface,
            show_x,
            extra_legend: &extra,
        };
        let mut chart = self.panel(area, legend, &spec)?;
        let (t0, t1) = self.time_range();
        if show_surface {
            chart.draw_series(DashedLineSeries::new(
                [(t0, surface_mm), (t1, surface_mm)],
                10,
                6,
                brown.stroke_width(2),
            ))?;
        }
        let s = self.summary;
        let apex = (s.apex_time_s, 1e3 * s.jump_height_m);
        chart.draw_series([Circle::new(apex, 8, BLACK.stroke_width(2))])?;
        let text = format!("jump height {:.1} mm", 1e3 * s.jump_height_m);
        let style = TextStyle::from((FONT, 20).into_font()).color(&BLACK);
        // Annotate left of the apex when the apex is in the right part of the plot.
        let right_side = (apex.0 - t0) / (t1 - t0) > 0.6;
        let pos = chart.backend_coord(&apex);
        let (w, _) = area.estimate_text_size(&text, &style)?;
        let x = if right_side {
            pos.0 - w as i32 - 16
        } else {
            pos.0 + 16
        };
        let (ox, oy) = area.get_base_pixel();
        area.draw(&Text::new(text, (x - ox, pos.1 - oy - 10), style))?;
        Ok(())
    }

    fn draw_forces<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        legend: &DrawingArea<DB, Shift>,
        show_x: bool,
    ) -> PlotResult<()> {
        let traces = [
            Trace {
                label: "spring F_s (> 0: compressed)",
                color: palette(4),
                column: |r| r.f_s,
                origin: 0.0,
                scale: 1.0,
            },
            Trace {
                label: "ground F_GM on foot",
                color: palette(5),
                column: |r| r.f_gm,
                origin: 0.0,
                scale: 1.0,
            },
        ];
        let spec = Panel {
            y_desc: "force (N)",
            traces: &traces,
            extra_y: &[0.0],
            show_x,
            extra_legend: &[],
        };
        self.panel(area, legend, &spec)?;
        Ok(())
    }

    fn draw_added_mass<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        legend: &DrawingArea<DB, Shift>,
    ) -> PlotResult<()> {
        let traces = [Trace {
            label: "added mass m_a",
            color: palette(1),
            column: |r| r.m_a,
            origin: 0.0,
            scale: 1e3,
        }];
        let spec = Panel {
            y_desc: "added mass m_a (g)",
            traces: &traces,
            extra_y: &[0.0],
            show_x: true,
            extra_legend: &[],
        };
        self.panel(area, legend, &spec)?;
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
            (1500, 1150)
        } else {
            (1500, 950)
        }
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult<()> {
        let root = root.margin(14, 6, 6, 6);
        let note = self.summary.final_height_note();
        let (head, body) = root.split_vertically(if note.is_some() { 110 } else { 80 });
        head.draw(&Text::new(
            self.title.clone(),
            (Y_LABEL_AREA as i32, 6),
            (FONT, 30).into_font().style(FontStyle::Bold).color(&BLACK),
        ))?;
        head.draw(&Text::new(
            self.subtitle(),
            (Y_LABEL_AREA as i32, 46),
            (FONT, 21).into_font().color(&RGBColor(70, 70, 70)),
        ))?;
        if let Some(note) = note {
            head.draw(&Text::new(
                format!("final (push-off) height not positive: {note}"),
                (Y_LABEL_AREA as i32, 76),
                (FONT, 21).into_font().color(&RGBColor(170, 40, 30)),
            ))?;
        }
        let w = body.dim_in_pixel().0;
        let (plots, legends) = body.split_horizontally(w.saturating_sub(LEGEND_WIDTH));
        let h = plots.dim_in_pixel().1;
        let split = |area: &DrawingArea<DB, Shift>, at: &[u32]| {
            area.split_by_breakpoints([] as [u32; 0], at)
        };
        if self.has_added_mass() {
            let at = [h * 45 / 100, h * 75 / 100];
            let (p, l) = (split(&plots, &at), split(&legends, &at));
            self.draw_heights(&p[0], &l[0], false)?;
            self.draw_forces(&p[1], &l[1], false)?;
            self.draw_added_mass(&p[2], &l[2])?;
        } else {
            let at = [h * 58 / 100];
            let (p, l) = (split(&plots, &at), split(&legends, &at));
            self.draw_heights(&p[0], &l[0], false)?;
            self.draw_forces(&p[1], &l[1], true)?;
        }
        Ok(())
    }
}
