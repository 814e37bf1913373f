//! Figures 5 and 6 from time series: the added mass during a stutter jump at phi = 0.57 in
//! units of the foot mass, and the paper's mechanism figure, one stutter jump under eq1 and
//! eq4 side by side (positions, spring force, ground force, added mass).

use sandjumper_core::trajectory::JumpKind;
use serde::Serialize;

use super::grid::GridFigure;
use super::sweeps::LOW_PHI;
use sandjumper_model::hybrid::GroundMode;
use sandjumper_model::jump::{JumpOutcome, JumpSpec, simulate_jump};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::record::SeriesRow;
use sandjumper_output::plot::lines::{Line, LinePanel};
use sandjumper_output::plot::palette;

/// Spacing of the recorded series, s.
const SERIES_INTERVAL_S: f64 = 2e-4;

/// One stutter jump at [`LOW_PHI`] with its time series.
pub fn stutter(model: ModelName, freq_hz: f64, rtol: f64) -> Result<(Params, JumpOutcome), String> {
    let params = Params::preset(LOW_PHI).map_err(|e| e.to_string())?;
    let spec = JumpSpec {
        kind: JumpKind::Stutter,
        freq_hz,
        tau_s: 0.0,
        model,
    };
    let opts = SimOptions {
        rtol,
        record_series: true,
        series_interval_s: SERIES_INTERVAL_S,
        ..SimOptions::default()
    };
    let out = simulate_jump(&params, &spec, &opts)
        .map_err(|e| format!("stutter jump, {model}, f = {freq_hz} Hz: {e}"))?;
    Ok((params, out))
}

/// A row of `added_mass_stutter.csv` / `mechanism.csv`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SeriesCsvRow {
    /// Ground model.
    pub model: String,
    /// Time, s.
    pub t_s: f64,
    /// Rod height above its rest height, m.
    pub rod_height_m: f64,
    /// Foot height (0 = undisturbed surface), m.
    pub x_f_m: f64,
    /// Motor position relative to the rod, m.
    pub p_m: f64,
    /// Spring force, N.
    pub f_s_n: f64,
    /// Ground force, N.
    pub f_gm_n: f64,
    /// Added mass, kg.
    pub m_a_kg: f64,
    /// Added mass in units of the foot mass.
    pub m_a_over_m_f: f64,
    /// Ground mode.
    pub mode: String,
}

/// Header of the series CSVs.
pub const HEADER: [&str; 10] = [
    "model",
    "t_s",
    "rod_height_m",
    "x_f_m",
    "p_m",
    "f_s_n",
    "f_gm_n",
    "m_a_kg",
    "m_a_over_m_f",
    "mode",
];

/// The CSV rows of one run.
pub fn csv_rows(model: ModelName, params: &Params, rows: &[SeriesRow]) -> Vec<SeriesCsvRow> {
    let x_r0 = rows.first().map_or(0.0, |r| r.x_r);
    rows.iter()
        .map(|r| SeriesCsvRow {
            model: model.as_str().into(),
            t_s: r.t_s,
            rod_height_m: r.x_r - x_r0,
            x_f_m: r.x_f,
            p_m: r.p,
            f_s_n: r.f_s,
            f_gm_n: r.f_gm,
            m_a_kg: r.m_a,
            m_a_over_m_f: r.m_a / params.robot.foot_mass_kg,
            mode: r.mode.as_str().into(),
        })
        .collect()
}

/// Figure 5: `m_a / m_f` against depth, one line per intrusion episode; and against time.
pub fn added_mass_figure(rows: &[SeriesCsvRow], freq_hz: f64) -> GridFigure {
    let mut episodes: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut inside = false;
    let mut starts = Vec::new();
    for r in rows {
        let intruding = r.mode == GroundMode::Intruding.as_str();
        if intruding && !inside {
            episodes.push(Vec::new());
            starts.push(r.t_s);
        }
        if intruding && let Some(e) = episodes.last_mut() {
            e.push((-1e3 * r.x_f_m, r.m_a_over_m_f));
        }
        inside = intruding;
    }
    let depth_lines = episodes
        .into_iter()
        .zip(starts)
        .enumerate()
        .filter(|(_, (e, _))| e.len() > 1)
        .map(|(i, (points, t0))| Line {
            label: format!("intrusion from t = {t0:.3} s"),
            points,
            color: palette(i),
            dashed: false,
            markers: false,
        })
        .collect();
    GridFigure::row(
        format!("Added mass during a stutter jump (eq4, φ = {LOW_PHI}, f = {freq_hz} Hz)"),
        vec![
            LinePanel {
                caption: "against foot depth, while intruding".into(),
                x_desc: "foot depth z (mm)".into(),
                y_desc: "added mass m_a / foot mass m_f".into(),
                lines: depth_lines,
                y_from_zero: true,
            },
            LinePanel {
                caption: "against time".into(),
                x_desc: "time t (s)".into(),
                y_desc: "added mass m_a / foot mass m_f".into(),
                lines: vec![Line {
                    label: String::new(),
                    points: rows.iter().map(|r| (r.t_s, r.m_a_over_m_f)).collect(),
                    color: palette(0),
                    dashed: false,
                    markers: false,
                }],
                y_from_zero: true,
            },
        ],
    )
}

/// Figure 6: one stutter jump under eq1 (solid) and eq4 (dashed): positions, spring force,
/// ground force, added mass.
pub fn mechanism_figure(eq1: &[SeriesCsvRow], eq4: &[SeriesCsvRow], freq_hz: f64) -> GridFigure {
    let runs = [(ModelName::Eq1, eq1, false), (ModelName::Eq4, eq4, true)];
    let series = |f: fn(&SeriesCsvRow) -> f64, color_offset: usize, what: &str| -> Vec<Line> {
        runs.iter()
            .enumerate()
            .map(|(i, (model, rows, dashed))| Line {
                label: format!("{what}{model}"),
                points: rows.iter().map(|r| (r.t_s, f(r))).collect(),
                color: palette(i + color_offset),
                dashed: *dashed,
                markers: false,
            })
            .collect()
    };
    let mut positions = series(|r| 1e3 * r.rod_height_m, 0, "rod height, ");
    positions.extend(series(|r| 1e3 * r.x_f_m, 2, "foot height, "));
    let panel = |caption: &str, y_desc: &str, lines: Vec<Line>| LinePanel {
        caption: caption.into(),
        x_desc: "time t (s)".into(),
        y_desc: y_desc.into(),
        lines,
        y_from_zero: false,
    };
    GridFigure::square(
        format!("Stutter jump at φ = {LOW_PHI}, f = {freq_hz} Hz: eq1 (solid) vs eq4 (dashed)"),
        vec![
            panel(
                "rod above rest, foot above the surface",
                "height (mm)",
                positions,
            ),
            panel(
                "spring force (> 0 compressed)",
                "F_s (N)",
                series(|r| r.f_s_n, 0, ""),
            ),
            panel(
                "ground force on the foot",
                "F_GM (N)",
                series(|r| r.f_gm_n, 0, ""),
            ),
            panel(
                "added mass (eq4 only)",
                "m_a / m_f",
                series(|r| r.m_a_over_m_f, 0, ""),
            ),
        ],
    )
}
