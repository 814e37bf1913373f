//! The run's dumps and force read back into the paper's measurements, in 3-D and grain by
//! grain (no azimuthal symmetry assumed):
//!
//! - the column's momentum `P = sum m_i (-v_z,i)` over the grains whose centres lie under
//!   the foot (horizontal distance to the axis `<= R`, below the foot's bottom): the paper's
//!   `rho phi int_0^H int_0^2pi int_0^R v r dr dpsi dh` summed over the grains themselves;
//!   the ring `R < r <= 2R` below the foot beside it, as a diagnostic;
//! - the added mass `m_a = P / v_foot` while the foot intrudes at least `min_speed_ratio`
//!   of its fastest (the paper's exclusion of `v -> 0`), against eq. 6 at the same depth
//!   with `C` scaled by `(R / 38 mm)^2`;
//! - the contact force on the foot against the model's `F_p(z)` for this foot;
//! - the jammed cone: the region under the foot that moves down with it. Over the frames
//!   with the paper's added mass, the grains' down speed over the foot's is averaged in
//!   cells of height (below the foot) and radius; at each height the cone's edge is the
//!   first radius where that mean falls below one half; a line through the edges inside the
//!   foot's radius gives the cone's angle to the horizontal, `atan(dh / -dr)` (the paper:
//!   about 60 degrees).

use serde::{Deserialize, Serialize};

use crate::bed::{FOOT, GRAIN};
use crate::dump::Frame;

/// Where the foot and the bed are.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// The foot's axis (x, y), m.
    pub axis_m: (f64, f64),
    /// Foot radius, m.
    pub foot_radius_m: f64,
    /// Radius of the foot's spheres, m.
    pub foot_sphere_radius_m: f64,
    /// The settled surface's height, m.
    pub surface_m: f64,
    /// Grain density, kg/m^3.
    pub grain_density_kg_m3: f64,
    /// Mean grain diameter, m.
    pub grain_diameter_m: f64,
    /// The time step, s.
    pub time_step_s: f64,
}

/// One row of `flow.csv`: one frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlowRow {
    /// Time since the intrusion's start, s.
    pub t_s: f64,
    /// Depth of the foot's bottom below the surface, m.
    pub depth_m: f64,
    /// The foot's down speed, m/s.
    pub foot_speed_m_s: f64,
    /// Momentum of the grains under the foot (down positive), kg m/s.
    pub momentum_under_foot_kg_m_s: f64,
    /// Grains under the foot.
    pub grains_under_foot: u64,
    /// Momentum of the grains in the ring `R < r <= 2R` below the foot (down positive),
    /// kg m/s.
    pub momentum_ring_kg_m_s: f64,
    /// The paper's added mass `P / v_foot` (NaN while the foot is slower than the rule
    /// allows), kg.
    pub added_mass_kg: f64,
    /// Eq. 6 at this depth for this foot (C scaled by (R / 38 mm)^2), kg.
    pub eq6_added_mass_kg: f64,
}

/// One row of `force_depth.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ForceRow {
    /// Window's end, s.
    pub t_s: f64,
    /// Depth of the foot's bottom, m.
    pub depth_m: f64,
    /// Contact force of the grains on the foot over the window (up positive), N.
    pub force_n: f64,
    /// The model's `F_p` at this depth for this foot, N.
    pub model_penetration_force_n: f64,
}

/// The foot's bottom height and down speed in a frame (None without foot spheres).
fn foot_of(frame: &Frame, g: &Geometry) -> Option<(f64, f64)> {
    let (mut zmin, mut vsum, mut n) = (f64::INFINITY, 0.0, 0u64);
    for a in frame.foot() {
        zmin = zmin.min(a.x[2]);
        vsum += -a.v[2];
        n += 1;
    }
    (n > 0).then(|| (zmin - g.foot_sphere_radius_m, vsum / n as f64))
}

/// The flow row of one frame (added mass not yet decided: NaN).
pub fn frame_row(frame: &Frame, g: &Geometry) -> Result<FlowRow, String> {
    let (bottom, v_foot) = foot_of(frame, g).ok_or_else(|| {
        format!(
            "the frame of step {} has no foot sphere (not a dump of this run's intrusion)",
            frame.step
        )
    })?;
    let r2 = g.foot_radius_m * g.foot_radius_m;
    let (mut p, mut n, mut ring) = (0.0, 0u64, 0.0);
    for a in frame
        .atoms
        .iter()
        .filter(|a| a.kind == GRAIN && a.x[2] < bottom)
    {
        let (dx, dy) = (a.x[0] - g.axis_m.0, a.x[1] - g.axis_m.1);
        let d2 = dx * dx + dy * dy;
        let m = g.grain_density_kg_m3 * 4.0 / 3.0 * core::f64::consts::PI * a.radius_m.powi(3);
        if d2 <= r2 {
            p += m * -a.v[2];
            n += 1;
        } else if d2 <= 4.0 * r2 {
            ring += m * -a.v[2];
        }
    }
    Ok(FlowRow {
        t_s: frame.step as f64 * g.time_step_s,
        depth_m: g.surface_m - bottom,
        foot_speed_m_s: v_foot,
        momentum_under_foot_kg_m_s: p,
        grains_under_foot: n,
        momentum_ring_kg_m_s: ring,
        added_mass_kg: f64::NAN,
        eq6_added_mass_kg: f64::NAN,
    })
}

/// Decide the added mass of every row (the paper's rule, `min_ratio` of the fastest
/// intrusion) and eq. 6's (`eq6(depth)`, kg) at each row's depth.
pub fn added_mass(
    rows: &mut [FlowRow],
    min_ratio: f64,
    eq6: &dyn Fn(f64) -> Result<f64, String>,
) -> Result<(), String> {
    let v_max = rows
        .iter()
        .filter(|r| r.depth_m > 0.0)
        .map(|r| r.foot_speed_m_s)
        .fold(0.0, f64::max);
    for r in rows.iter_mut() {
        r.eq6_added_mass_kg = if r.depth_m > 0.0 {
            eq6(r.depth_m)?
        } else {
            0.0
        };
        r.added_mass_kg = if r.depth_m > 0.0 {
            sandjumper_dem::intrude::paper_added_mass(
                r.momentum_under_foot_kg_m_s,
                r.foot_speed_m_s,
                v_max,
                min_ratio,
            )
        } else {
            f64::NAN
        };
    }
    Ok(())
}

/// Read `force.txt` (`fix ave/time`: step, time, force, the foot's lowest centre) into rows,
/// `fp(depth)` the model's force. Errors name the file and line.
pub fn read_force(
    path: &std::path::Path,
    g: &Geometry,
    fp: &dyn Fn(f64) -> Result<f64, String>,
) -> Result<Vec<ForceRow>, String> {
    let name = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: {e}"))?;
    let mut rows = Vec::new();
    for (no, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let f: Vec<f64> = l
            .split_whitespace()
            .map(|w| w.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("{name}:{}: `{l}` is not four numbers", no + 1))?;
        if f.len() != 4 {
            return Err(format!(
                "{name}:{}: {} values (allowed: step, time, force, lowest foot centre; the \
                 file is cut short or not of this run)",
                no + 1,
                f.len()
            ));
        }
        let depth = g.surface_m - (f[3] - g.foot_sphere_radius_m);
        rows.push(ForceRow {
            t_s: f[1],
            depth_m: depth,
            force_n: f[2],
            model_penetration_force_n: fp(depth)?,
        });
    }
    Ok(rows)
}

/// The cone's measure at one height below the foot: one row of `cone.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConeRow {
    /// Height below the foot's bottom (the bin's middle), m.
    pub below_foot_m: f64,
    /// The mean down speed over the foot's on the axis (the first radius bin), 1.
    pub axis_speed_ratio: f64,
    /// The cone's edge: the first radius whose mean speed ratio is below 1/2 (NaN: none
    /// within 1.5 R), m.
    pub edge_radius_m: f64,
}

/// The jammed cone.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cone {
    /// Angle of its side to the horizontal, degrees (None: not found, see `note`).
    pub angle_deg: Option<f64>,
    /// Apex below the foot's bottom, m.
    pub apex_below_foot_m: Option<f64>,
    /// Frames averaged.
    pub frames: u64,
    /// Why there is no angle, or how it was fitted.
    pub note: String,
    /// Its edge at each height.
    pub rows: Vec<ConeRow>,
}

/// Cells of (height below the foot, radius) accumulating grains' down speed over the foot's.
#[derive(Clone, Debug)]
pub struct ConeCells {
    dh: f64,
    dr: f64,
    heights: usize,
    radii: usize,
    sum: Vec<f64>,
    count: Vec<u64>,
    frames: u64,
    foot_radius_m: f64,
}

impl ConeCells {
    /// Cells one grain high and half a grain wide, down to 2.5 R, out to 1.5 R.
    pub fn new(g: &Geometry) -> Self {
        let (dh, dr) = (g.grain_diameter_m, 0.5 * g.grain_diameter_m);
        let heights = (2.5 * g.foot_radius_m / dh).ceil() as usize;
        let radii = (1.5 * g.foot_radius_m / dr).ceil() as usize;
        Self {
            dh,
            dr,
            heights,
            radii,
            sum: vec![0.0; heights * radii],
            count: vec![0; heights * radii],
            frames: 0,
            foot_radius_m: g.foot_radius_m,
        }
    }

    /// Add one frame whose row has the paper's added mass.
    pub fn add(&mut self, frame: &Frame, g: &Geometry, row: &FlowRow) {
        let bottom = g.surface_m - row.depth_m;
        let v = row.foot_speed_m_s;
        if v <= 0.0 {
            return;
        }
        self.frames += 1;
        for a in frame
            .atoms
            .iter()
            .filter(|a| a.kind != FOOT && a.x[2] < bottom)
        {
            let h = ((bottom - a.x[2]) / self.dh) as usize;
            let (dx, dy) = (a.x[0] - g.axis_m.0, a.x[1] - g.axis_m.1);
            let r = ((dx * dx + dy * dy).sqrt() / self.dr) as usize;
            if h < self.heights && r < self.radii {
                let k = h * self.radii + r;
                self.sum[k] += -a.v[2] / v;
                self.count[k] += 1;
            }
        }
    }

    /// The cone from the cells.
    pub fn cone(&self) -> Cone {
        let mut rows = Vec::new();
        for h in 0..self.heights {
            let mean = |r: usize| {
                let k = h * self.radii + r;
                (self.count[k] > 0).then(|| self.sum[k] / self.count[k] as f64)
            };
            let axis = mean(0).unwrap_or(f64::NAN);
            let edge = (0..self.radii)
                .find(|&r| mean(r).is_some_and(|m| m < 0.5))
                .map_or(f64::NAN, |r| r as f64 * self.dr);
            rows.push(ConeRow {
                below_foot_m: (h as f64 + 0.5) * self.dh,
                axis_speed_ratio: axis,
                edge_radius_m: edge,
            });
        }
        let side: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.edge_radius_m > 0.0 && r.edge_radius_m < 0.95 * self.foot_radius_m)
            .map(|r| (r.below_foot_m, r.edge_radius_m))
            .collect();
        let (angle, apex, note) = if self.frames == 0 {
            (
                None,
                None,
                "no frame with the paper's added mass".to_string(),
            )
        } else if side.len() < 3 {
            (
                None,
                None,
                format!(
                    "the co-moving region's edge lies inside the foot's radius at {} height(s) \
                     (a cone needs at least 3)",
                    side.len()
                ),
            )
        } else {
            let n = side.len() as f64;
            let (mh, mr) = (
                side.iter().map(|p| p.0).sum::<f64>() / n,
                side.iter().map(|p| p.1).sum::<f64>() / n,
            );
            let sxx: f64 = side.iter().map(|p| (p.0 - mh).powi(2)).sum();
            let sxy: f64 = side.iter().map(|p| (p.0 - mh) * (p.1 - mr)).sum();
            let slope = sxy / sxx;
            if slope >= 0.0 {
                (
                    None,
                    None,
                    "the co-moving region does not narrow with depth".to_string(),
                )
            } else {
                let a = mr - slope * mh;
                (
                    Some((1.0 / -slope).atan().to_degrees()),
                    Some(a / -slope),
                    format!(
                        "a line through the edge at {} heights, over {} frames",
                        side.len(),
                        self.frames
                    ),
                )
            }
        };
        Cone {
            angle_deg: angle,
            apex_below_foot_m: apex,
            frames: self.frames,
            note,
            rows,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dump::DumpAtom;

    fn geometry() -> Geometry {
        Geometry {
            axis_m: (0.03, 0.03),
            foot_radius_m: 0.01,
            foot_sphere_radius_m: 0.0009,
            surface_m: 0.04,
            grain_density_kg_m3: 1000.0,
            grain_diameter_m: 0.001,
            time_step_s: 1e-5,
        }
    }

    /// A foot at `bottom` moving down at `v`, and grains on a lattice below it: those inside
    /// a 60 degree cone of the foot's radius move with it, the others are at rest.
    fn cone_frame(bottom: f64, v: f64) -> Frame {
        let g = geometry();
        let mut atoms = vec![DumpAtom {
            id: 1,
            kind: FOOT,
            x: [0.03, 0.03, bottom + 0.0009],
            v: [0.0, 0.0, -v],
            radius_m: 0.0009,
        }];
        let tan = 60f64.to_radians().tan();
        let s = 0.0005;
        for i in -40..=40 {
            for j in -40..=40 {
                for k in 1..60 {
                    let (x, y, h) = (i as f64 * s, j as f64 * s, k as f64 * s);
                    let r = (x * x + y * y).sqrt();
                    let inside = r <= g.foot_radius_m - h / tan;
                    atoms.push(DumpAtom {
                        id: atoms.len() as u64 + 1,
                        kind: GRAIN,
                        x: [0.03 + x, 0.03 + y, bottom - h],
                        v: [0.0, 0.0, if inside { -v } else { 0.0 }],
                        radius_m: 0.0005,
                    });
                }
            }
        }
        Frame { step: 1000, atoms }
    }

    #[test]
    fn the_column_momentum_and_a_60_degree_cone_are_measured() {
        let g = geometry();
        let frame = cone_frame(0.03, 0.2);
        let row = frame_row(&frame, &g).unwrap();
        assert!((row.depth_m - 0.01).abs() < 1e-12);
        assert!((row.foot_speed_m_s - 0.2).abs() < 1e-12);
        assert!((row.t_s - 0.01).abs() < 1e-12);
        // The column's momentum is the co-moving cone's mass times v: count them.
        let m = 1000.0 * 4.0 / 3.0 * core::f64::consts::PI * 0.0005f64.powi(3);
        let moving = frame
            .atoms
            .iter()
            .filter(|a| a.kind == GRAIN && a.v[2] < 0.0)
            .count() as f64;
        assert!((row.momentum_under_foot_kg_m_s - moving * m * 0.2).abs() < 1e-12);
        assert_eq!(row.momentum_ring_kg_m_s, 0.0);
        let mut cells = ConeCells::new(&g);
        cells.add(&frame, &g, &row);
        let cone = cells.cone();
        let angle = cone.angle_deg.unwrap();
        assert!((angle - 60.0).abs() < 4.0, "{angle} {}", cone.note);
        let apex = cone.apex_below_foot_m.unwrap();
        assert!(
            (apex - 0.01 * 60f64.to_radians().tan()).abs() < 0.002,
            "{apex}"
        );
    }

    #[test]
    fn the_added_mass_follows_the_papers_speed_rule() {
        let mut rows: Vec<FlowRow> = [(0.001, 0.2), (0.005, 0.3), (0.009, 0.05)]
            .iter()
            .map(|&(d, v)| FlowRow {
                t_s: 0.0,
                depth_m: d,
                foot_speed_m_s: v,
                momentum_under_foot_kg_m_s: 0.003,
                grains_under_foot: 1,
                momentum_ring_kg_m_s: 0.0,
                added_mass_kg: f64::NAN,
                eq6_added_mass_kg: f64::NAN,
            })
            .collect();
        added_mass(&mut rows, 0.3, &|d| Ok(d)).unwrap();
        assert!((rows[0].added_mass_kg - 0.015).abs() < 1e-12);
        assert!((rows[1].added_mass_kg - 0.01).abs() < 1e-12);
        assert!(rows[2].added_mass_kg.is_nan(), "0.05 < 0.3 x 0.3 m/s");
        assert_eq!(rows[2].eq6_added_mass_kg, 0.009);
    }
}
