//! Figure 4: the quasi-static penetration force `F_p(z)` of the two-resistance and cone laws
//! at several packing fractions, and a slow re-intrusion (intrude, withdraw, intrude again).

use serde::Serialize;

use super::grid::GridFigure;

use sandjumper_model::ground::{DragLaw, GroundLaw, PenetrationLaw, Sand};
use sandjumper_model::params::{Params, ReintrusionAnchor};
use sandjumper_output::plot::lines::{Line, LinePanel};
use sandjumper_output::plot::palette;

/// Packing fractions of the `F_p(z)` panel.
pub const LAW_PHIS: [f64; 4] = [0.57, 0.59, 0.61, 0.62];
/// Deepest depth drawn, m.
const DEPTH_MAX_M: f64 = 0.05;
/// Depth where the slow re-intrusion test withdraws the foot and comes back, m.
pub const REINTRUSION_START_M: f64 = 0.02;

/// One point of a force-depth curve (a row of `penetration_force.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ForceDepthRow {
    /// `two-resistance`, `cone`, or `<law> re-intrusion`.
    pub curve: String,
    /// Packing fraction.
    pub phi: f64,
    /// Depth below the free surface, m.
    pub depth_m: f64,
    /// Force the sand resists with, N.
    pub force_n: f64,
}

/// Header of `penetration_force.csv`.
pub const HEADER: [&str; 4] = ["curve", "phi", "depth_m", "force_n"];

fn law_name(law: PenetrationLaw) -> &'static str {
    match law {
        PenetrationLaw::TwoResistance => "two-resistance",
        PenetrationLaw::Cone => "cone",
        PenetrationLaw::Linear => "linear",
        PenetrationLaw::Rigid => "rigid",
    }
}

fn sand(phi: f64, penetration: PenetrationLaw) -> Result<Sand, String> {
    let params = Params::preset(phi).map_err(|e| e.to_string())?;
    let law = GroundLaw {
        penetration,
        reintrusion: true,
        anchor: ReintrusionAnchor::Episode,
        drag: DragLaw::ConstantAlpha,
    };
    Ok(Sand::new(&params, law))
}

/// The curves: `F_p(z)` for both laws at [`LAW_PHIS`]; at 0.57 the slow re-intrusion of both
/// laws (first intrusion to [`REINTRUSION_START_M`], withdrawal, re-intrusion deeper).
pub fn curves() -> Result<Vec<ForceDepthRow>, String> {
    let n = 200;
    let depths: Vec<f64> = (0..=n)
        .map(|i| DEPTH_MAX_M * f64::from(i) / f64::from(n))
        .collect();
    let mut rows = Vec::new();
    for law in [PenetrationLaw::TwoResistance, PenetrationLaw::Cone] {
        for phi in LAW_PHIS {
            let s = sand(phi, law)?;
            rows.extend(depths.iter().map(|&z| ForceDepthRow {
                curve: law_name(law).into(),
                phi,
                depth_m: z,
                force_n: s.penetration_force(z),
            }));
        }
        let s = sand(LAW_PHIS[0], law)?;
        let z0 = REINTRUSION_START_M;
        let curve = format!("{} re-intrusion", law_name(law));
        let point = |z: f64, f: f64| ForceDepthRow {
            curve: curve.clone(),
            phi: LAW_PHIS[0],
            depth_m: z,
            force_n: f,
        };
        rows.extend(
            depths
                .iter()
                .filter(|&&z| z <= z0)
                .map(|&z| point(z, s.penetration_force(z))),
        );
        rows.push(point(z0, 0.0)); // withdrawn: the load is off
        rows.extend(
            depths
                .iter()
                .filter(|&&z| z >= z0)
                .map(|&z| point(z, s.resisting_force(z, Some(z0)))),
        );
    }
    Ok(rows)
}

/// The figure: left `F_p(z)` (two-resistance solid, cone dashed), right the re-intrusion.
pub fn figure(rows: &[ForceDepthRow]) -> GridFigure {
    let line = |curve: &str, phi: f64| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.curve == curve && (r.phi - phi).abs() < 1e-9)
            .map(|r| (1e3 * r.depth_m, r.force_n))
            .collect()
    };
    let mut left = Vec::new();
    for (i, phi) in LAW_PHIS.into_iter().enumerate() {
        left.push(Line {
            label: format!("φ = {phi}"),
            points: line("two-resistance", phi),
            color: palette(i),
            dashed: false,
            markers: false,
        });
        left.push(Line {
            label: if i == 0 {
                "dashed: cone (RFT) law".into()
            } else {
                String::new()
            },
            points: line("cone", phi),
            color: palette(i),
            dashed: true,
            markers: false,
        });
    }
    let phi = LAW_PHIS[0];
    let right = vec![
        Line {
            label: "two-resistance".into(),
            points: line("two-resistance re-intrusion", phi),
            color: palette(0),
            dashed: false,
            markers: false,
        },
        Line {
            label: "two-resist., plain F_p".into(),
            points: line("two-resistance", phi),
            color: palette(0),
            dashed: true,
            markers: false,
        },
        Line {
            label: "cone".into(),
            points: line("cone re-intrusion", phi),
            color: palette(1),
            dashed: false,
            markers: false,
        },
        Line {
            label: "cone, plain F_p".into(),
            points: line("cone", phi),
            color: palette(1),
            dashed: true,
            markers: false,
        },
    ];
    GridFigure::row(
        "Quasi-static penetration force F_p(z)",
        vec![
            LinePanel {
                caption: "two-resistance (solid) and cone (dashed) laws".into(),
                x_desc: "depth z (mm)".into(),
                y_desc: "penetration force F_p (N)".into(),
                lines: left,
                y_from_zero: true,
            },
            LinePanel {
                caption: format!(
                    "slow re-intrusion from z = {:.0} mm, φ = {phi}",
                    1e3 * REINTRUSION_START_M
                ),
                x_desc: "depth z (mm)".into(),
                y_desc: "force on the foot (N)".into(),
                lines: right,
                y_from_zero: true,
            },
        ],
    )
}
