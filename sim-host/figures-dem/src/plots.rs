//! The comparison's figures: added mass against depth with eq. 6, momentum against time
//! for the three jumps, PIV against the DEM, the shear bands, the sensitivity rows.

use std::path::Path;

use serde::Serialize;

use crate::compare::{PivComparison, Row, read_table, val};
use crate::error::FiguresDemError;
use sandjumper_flow::cone::{BandRow, ShearBandCone};
use sandjumper_output::StagedDir;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel};
use sandjumper_output::plot::{palette, save_figure};

/// One sample of a push-off's column momentum (a row of `momentum_vs_time.csv`).
#[derive(Clone, Debug, Serialize)]
pub struct SeriesRow {
    /// The jump (`single`, `stutter`, `delayed`).
    pub jump: String,
    /// Time from the push-off's start, s.
    pub t_s: f64,
    /// The foot's depth, m.
    pub depth_m: f64,
    /// Momentum of the column under the foot, kg m/s.
    pub momentum_under_foot_kg_m_s: f64,
    /// The paper's added mass, kg (NaN: the foot too slow).
    pub added_mass_kg: f64,
    /// Eq. 6 at this depth for this foot (`C` scaled by `(R / 38 mm)^2`), kg.
    pub eq6_added_mass_kg: f64,
    /// The per-depth curve of the headline: the added mass over eq. 6's, 1 (NaN: no added
    /// mass at this sample, or eq. 6 zero).
    pub added_mass_vs_eq6: f64,
    /// Whether this depth is where eq. 6's cone is forming (the headline's samples): 1 or 0.
    pub in_cone_forming_depths: u8,
}

/// The highest DEM/eq. 6 ratio the per-depth figure draws (the first samples at contact,
/// where eq. 6 is near zero, go far above it; `momentum_vs_time.csv` has them all).
const RATIO_AXIS_TOP: f64 = 10.0;

/// The figures: added mass against depth with eq. 6, momentum against time for the three
/// jumps, PIV against the DEM, the sensitivity rows. Returns the momentum series.
pub fn figures(
    staged: &StagedDir,
    runs: &Path,
    phi: f64,
    radius_m: f64,
    rows: &[(Row, Option<ShearBandCone>)],
    piv: &PivComparison,
) -> Result<Vec<SeriesRow>, FiguresDemError> {
    let mut series = Vec::new();
    let mut am_lines = Vec::new();
    let mut p_lines = Vec::new();
    let mut ratio_lines = Vec::new();
    let mut zmax: f64 = 1e-4;
    let (from, to) = sandjumper_flow::momentum::cone_forming_depths(phi, radius_m)
        .map_err(FiguresDemError::internal)?;
    for (k, kind) in ["single", "stutter", "delayed"].iter().enumerate() {
        let t = read_table(&runs.join(kind).join("flow.csv"))?;
        let first = series.len();
        for r in &t {
            let depth_m = val(r, "depth_m");
            let added_mass_kg = val(r, "added_mass_kg");
            let eq6 = if depth_m > 0.0 {
                sandjumper_flow::momentum::model_added_mass(phi, radius_m, depth_m)
                    .map_err(FiguresDemError::internal)?
            } else {
                0.0
            };
            series.push(SeriesRow {
                jump: kind.to_string(),
                t_s: val(r, "t_s"),
                depth_m,
                momentum_under_foot_kg_m_s: val(r, "momentum_under_foot_kg_m_s"),
                added_mass_kg,
                eq6_added_mass_kg: eq6,
                added_mass_vs_eq6: if eq6 > 0.0 {
                    added_mass_kg / eq6
                } else {
                    f64::NAN
                },
                in_cone_forming_depths: u8::from((from..=to).contains(&depth_m)),
            });
        }
        ratio_lines.push(Line {
            label: kind.to_string(),
            points: series[first..]
                .iter()
                .filter(|q| {
                    q.added_mass_vs_eq6.is_finite() && q.added_mass_vs_eq6 <= RATIO_AXIS_TOP
                })
                .map(|q| (1e3 * q.depth_m, q.added_mass_vs_eq6))
                .collect(),
            color: palette(k),
            dashed: false,
            markers: true,
        });
        let am: Vec<(f64, f64)> = t
            .iter()
            .filter(|r| val(r, "added_mass_kg").is_finite() && val(r, "depth_m") > 0.0)
            .map(|r| (1e3 * val(r, "depth_m"), val(r, "added_mass_kg")))
            .collect();
        zmax = am.iter().map(|p| p.0 / 1e3).fold(zmax, f64::max);
        am_lines.push(Line {
            label: format!("DEM, {kind}"),
            points: am,
            color: palette(k),
            dashed: false,
            markers: true,
        });
        p_lines.push(Line {
            label: kind.to_string(),
            points: t
                .iter()
                .map(|r| (1e3 * val(r, "t_s"), val(r, "momentum_under_foot_kg_m_s")))
                .collect(),
            color: palette(k),
            dashed: false,
            markers: true,
        });
    }
    // The paper's relative scaling (Fig. 4a inset): each jump's momentum over the stutter's
    // peak.
    let stutter_peak = series
        .iter()
        .filter(|r| r.jump == "stutter")
        .map(|r| r.momentum_under_foot_kg_m_s)
        .fold(f64::NAN, f64::max);
    let rel_lines: Vec<Line> = p_lines
        .iter()
        .map(|l| Line {
            points: l
                .points
                .iter()
                .map(|&(t, p)| (t, p / stutter_peak))
                .collect(),
            ..l.clone()
        })
        .collect();
    let eq6: Vec<(f64, f64)> = (0..=60)
        .filter_map(|i| {
            let z = zmax * f64::from(i) / 60.0;
            sandjumper_flow::momentum::model_added_mass(phi, radius_m, z)
                .ok()
                .map(|m| (1e3 * z, m))
        })
        .collect();
    am_lines.push(Line {
        label: "eq. 6, C scaled by (R / 38 mm)^2".into(),
        points: eq6,
        color: palette(3),
        dashed: true,
        markers: false,
    });
    am_lines.push(Line {
        label: "PIV on the stutter's frames".into(),
        points: piv
            .points
            .iter()
            .map(|q| (1e3 * q.depth_m, q.piv_added_mass_kg))
            .collect(),
        color: palette(4),
        dashed: true,
        markers: true,
    });
    let fig = LineFigure {
        title: "DEM added mass (column under the foot, v >= 0.3 v_max) and eq. 6".into(),
        panels: vec![
            LinePanel {
                caption: format!("three push-offs, paper model, 0.70; phi {phi}"),
                x_desc: "depth (mm)".into(),
                y_desc: "added mass (kg)".into(),
                lines: am_lines,
                y_from_zero: true,
            },
            LinePanel {
                caption: "momentum under the foot".into(),
                x_desc: "time from the push-off's start (ms)".into(),
                y_desc: "P (kg m/s)".into(),
                lines: p_lines,
                y_from_zero: false,
            },
            LinePanel {
                caption: "relative to the stutter's peak (Fig. 4a inset)".into(),
                x_desc: "time from the push-off's start (ms)".into(),
                y_desc: "P / P_max(stutter)".into(),
                lines: rel_lines,
                y_from_zero: false,
            },
        ],
        size: (2000, 600),
    };
    save_figure(
        &fig,
        &staged.file("added_mass_and_momentum.png"),
        Some(&staged.file("added_mass_and_momentum.svg")),
    )?;
    // The headline's per-depth curve: DEM over eq. 6 at each sample's depth, the depths
    // where eq. 6's cone is forming marked.
    let top = ratio_lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.1))
        .fold(1.0f64, f64::max);
    let off_scale = series
        .iter()
        .filter(|q| q.added_mass_vs_eq6 > RATIO_AXIS_TOP)
        .count();
    for (edge, label) in [
        (from, "eq. 6 a quarter formed"),
        (to, "eq. 6's cone complete"),
    ] {
        if edge <= zmax {
            ratio_lines.push(Line {
                label: label.into(),
                points: vec![(1e3 * edge, 0.0), (1e3 * edge, top)],
                color: palette(7),
                dashed: true,
                markers: false,
            });
        }
    }
    let by_depth = LineFigure {
        title: "DEM / eq. 6 by depth (the headline: the median between the dashed lines)".into(),
        panels: vec![LinePanel {
            caption: format!(
                "eq. 6's cone forms: {:.1} mm (a quarter) to {:.1} mm (complete); phi {phi}, R \
                 {:.0} mm; {off_scale} samples above {RATIO_AXIS_TOP} not drawn",
                1e3 * from,
                1e3 * to,
                1e3 * radius_m
            ),
            x_desc: "depth (mm)".into(),
            y_desc: "DEM added mass / eq. 6".into(),
            lines: ratio_lines,
            y_from_zero: true,
        }],
        size: (1400, 650),
    };
    save_figure(
        &by_depth,
        &staged.file("added_mass_vs_eq6_by_depth.png"),
        Some(&staged.file("added_mass_vs_eq6_by_depth.svg")),
    )?;
    // The shear bands' positions below the foot per run, with the paper's 60 degree cone.
    let mut band_lines = Vec::new();
    for (k, (r, cone)) in rows.iter().enumerate() {
        let Some(cone) = cone else {
            continue;
        };
        let pt =
            |b: &BandRow, side: f64, sign: f64| (sign * 1e3 * side, -1e3 * b.depth_below_foot_m);
        for sign in [-1.0, 1.0] {
            band_lines.push(Line {
                label: if sign < 0.0 {
                    r.name.clone()
                } else {
                    String::new()
                },
                points: cone
                    .rows
                    .iter()
                    .map(|b| pt(b, if sign < 0.0 { b.left_m } else { b.right_m }, sign))
                    .collect(),
                color: palette(k),
                dashed: false,
                markers: true,
            });
        }
    }
    let apex = 1e3 * radius_m * 60f64.to_radians().tan();
    band_lines.push(Line {
        label: "60 deg cone (the paper)".into(),
        points: vec![(-1e3 * radius_m, 0.0), (0.0, -apex), (1e3 * radius_m, 0.0)],
        color: palette(7),
        dashed: true,
        markers: false,
    });
    let cone_fig = LineFigure {
        title: "Shear bands below the foot (strain-rate peaks, foot frame, v >= 0.3 v_max)".into(),
        panels: vec![LinePanel {
            caption: "each run's band positions row by row, down to the first row without bands"
                .into(),
            x_desc: "distance from the foot's axis (mm)".into(),
            y_desc: "height below the foot's bottom (mm)".into(),
            lines: band_lines,
            y_from_zero: false,
        }],
        size: (900, 700),
    };
    save_figure(
        &cone_fig,
        &staged.file("shear_bands.png"),
        Some(&staged.file("shear_bands.svg")),
    )?;
    // The sensitivity rows and the cones as one bar-like figure: ratio per run.
    let rows: Vec<&Row> = rows.iter().map(|(r, _)| r).collect();
    let sens = LineFigure {
        title: "DEM / eq. 6 and the jammed cone per run".into(),
        panels: vec![
            LinePanel {
                caption: rows
                    .iter()
                    .enumerate()
                    .map(|(i, r)| format!("{}: {}", i + 1, r.name))
                    .collect::<Vec<_>>()
                    .join(", "),
                x_desc: "run".into(),
                y_desc: "DEM / eq. 6 (median)".into(),
                lines: vec![Line {
                    label: "DEM / eq. 6".into(),
                    points: rows
                        .iter()
                        .enumerate()
                        .map(|(i, r)| ((i + 1) as f64, r.added_mass_vs_eq6_median))
                        .collect(),
                    color: palette(0),
                    dashed: false,
                    markers: true,
                }],
                y_from_zero: true,
            },
            LinePanel {
                caption: "cone side from the horizontal (the paper: about 60 deg); missing: none"
                    .into(),
                x_desc: "run".into(),
                y_desc: "angle (deg)".into(),
                lines: vec![
                    Line {
                        label: "shear-band cone".into(),
                        points: rows
                            .iter()
                            .enumerate()
                            .filter(|(_, r)| r.shear_band_cone_deg.is_finite())
                            .map(|(i, r)| ((i + 1) as f64, r.shear_band_cone_deg))
                            .collect(),
                        color: palette(1),
                        dashed: false,
                        markers: true,
                    },
                    Line {
                        label: "co-moving cone".into(),
                        points: rows
                            .iter()
                            .enumerate()
                            .filter(|(_, r)| r.comoving_cone_deg.is_finite())
                            .map(|(i, r)| ((i + 1) as f64, r.comoving_cone_deg))
                            .collect(),
                        color: palette(2),
                        dashed: false,
                        markers: true,
                    },
                ],
                y_from_zero: true,
            },
        ],
        size: (1400, 600),
    };
    save_figure(
        &sens,
        &staged.file("sensitivity.png"),
        Some(&staged.file("sensitivity.svg")),
    )?;
    Ok(series)
}
