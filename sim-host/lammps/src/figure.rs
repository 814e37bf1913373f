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
    cone: Option<&Cone>,
    cone_note: &str,
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
    let rows = cone.map_or(&[][..], |c| &c.rows[..]);
    let mut cone_lines = vec![
        line(
            "edges: down speed half the foot's",
            rows.iter()
                .map(|r| (-mm * r.left_m, -mm * r.depth_below_foot_m))
                .collect(),
            0,
            false,
            true,
        ),
        line(
            "",
            rows.iter()
                .map(|r| (mm * r.right_m, -mm * r.depth_below_foot_m))
                .collect(),
            0,
            false,
            true,
        ),
    ];
    if let Some(c) = cone.filter(|c| c.angle_deg.is_finite() && c.apex_depth_m.is_finite()) {
        let r0 = c.apex_depth_m / c.angle_deg.to_radians().tan();
        cone_lines.push(line(
            &format!("fitted sides, {:.0} deg", c.angle_deg),
            vec![(-mm * r0, 0.0), (0.0, -mm * c.apex_depth_m), (mm * r0, 0.0)],
            1,
            true,
            false,
        ));
    }
    cone_lines.push(line(
        "foot",
        vec![(-mm * foot_radius_m, 0.0), (mm * foot_radius_m, 0.0)],
        3,
        false,
        false,
    ));
    let cone_panel = LinePanel {
        caption: match cone.map(|c| c.angle_deg).filter(|a| a.is_finite()) {
            Some(a) => format!("jammed cone: {a:.0} deg to the horizontal (paper ~60)"),
            None => format!("jammed cone: none ({cone_note})"),
        },
        x_desc: "distance from the axis (mm)".into(),
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
