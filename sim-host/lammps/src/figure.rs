//! `lammps.png` / `lammps.svg`: the added mass against eq. 6 with depth, the force against
//! `F_p(z)`, the column's momentum with time, and the jammed cone's edge.

use std::path::Path;

use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::{palette, save_figure};

use crate::analysis::{Cone, FlowRow, ForceRow};

fn line(label: &str, points: Vec<(f64, f64)>, colour: usize, dashed: bool, markers: bool) -> Line {
    Line {
        label: label.into(),
        points,
        color: palette(colour),
        dashed,
        markers,
    }
}

/// Draw the run's figure into `dir` as `lammps.png` and `lammps.svg`.
pub fn draw(
    dir: &Path,
    title: &str,
    flow: &[FlowRow],
    force: &[ForceRow],
    cone: &Cone,
    foot_radius_m: f64,
) -> Result<(), String> {
    let mm = 1e3;
    let added = LinePanel {
        caption: "added mass: the column under the foot, P / v (the paper's rule)".into(),
        x_desc: "depth (mm)".into(),
        y_desc: "added mass (g)".into(),
        lines: vec![
            line(
                "3-D DEM (LAMMPS)",
                flow.iter()
                    .filter(|r| r.added_mass_kg.is_finite())
                    .map(|r| (mm * r.depth_m, 1e3 * r.added_mass_kg))
                    .collect(),
                0,
                false,
                true,
            ),
            line(
                "eq. 6, C scaled by (R / 38 mm)^2",
                flow.iter()
                    .filter(|r| r.depth_m > 0.0)
                    .map(|r| (mm * r.depth_m, 1e3 * r.eq6_added_mass_kg))
                    .collect(),
                1,
                true,
                false,
            ),
        ],
        y_from_zero: true,
    };
    let forces = LinePanel {
        caption: "force on the foot".into(),
        x_desc: "depth (mm)".into(),
        y_desc: "force (N)".into(),
        lines: vec![
            line(
                "3-D DEM (window means)",
                force.iter().map(|r| (mm * r.depth_m, r.force_n)).collect(),
                0,
                false,
                false,
            ),
            line(
                "model F_p(z) for this foot",
                force
                    .iter()
                    .filter(|r| r.depth_m > 0.0)
                    .map(|r| (mm * r.depth_m, r.model_penetration_force_n))
                    .collect(),
                1,
                true,
                false,
            ),
        ],
        y_from_zero: false,
    };
    let momentum = LinePanel {
        caption: "grain momentum (down positive)".into(),
        x_desc: "time (ms)".into(),
        y_desc: "momentum (g m/s)".into(),
        lines: vec![
            line(
                "column under the foot (r <= R)",
                flow.iter()
                    .map(|r| (mm * r.t_s, 1e3 * r.momentum_under_foot_kg_m_s))
                    .collect(),
                0,
                false,
                true,
            ),
            line(
                "ring R < r <= 2R",
                flow.iter()
                    .map(|r| (mm * r.t_s, 1e3 * r.momentum_ring_kg_m_s))
                    .collect(),
                2,
                true,
                false,
            ),
        ],
        y_from_zero: false,
    };
    let mut cone_lines = vec![line(
        "edge: down speed half the foot's",
        cone.rows
            .iter()
            .filter(|r| r.edge_radius_m.is_finite())
            .map(|r| (mm * r.edge_radius_m, -mm * r.below_foot_m))
            .collect(),
        0,
        false,
        true,
    )];
    if let (Some(angle), Some(apex)) = (cone.angle_deg, cone.apex_below_foot_m) {
        let r0 = apex / angle.to_radians().tan();
        cone_lines.push(line(
            &format!("fitted side, {angle:.0} deg"),
            vec![(mm * r0, 0.0), (0.0, -mm * apex)],
            1,
            true,
            false,
        ));
    }
    cone_lines.push(line(
        "foot",
        vec![(0.0, 0.0), (mm * foot_radius_m, 0.0)],
        3,
        false,
        false,
    ));
    let cone_panel = LinePanel {
        caption: match cone.angle_deg {
            Some(a) => format!("jammed cone: {a:.0} deg to the horizontal (paper ~60)"),
            None => format!("jammed cone: none ({})", cone.note),
        },
        x_desc: "radius (mm)".into(),
        y_desc: "height below the foot (mm)".into(),
        lines: cone_lines,
        y_from_zero: false,
    };
    let panels = vec![added, forces, momentum, cone_panel];
    let fig = LineFigure {
        title: title.into(),
        size: grid_size(panels.len()),
        panels,
    };
    save_figure(&fig, &dir.join("lammps.png"), Some(&dir.join("lammps.svg")))
        .map_err(|e| format!("cannot draw lammps.png: {e}"))
}
