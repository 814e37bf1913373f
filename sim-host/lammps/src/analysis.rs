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
//! - the jammed cone: the region under the foot that moves down with it, measured as the
//!   2-D DEM's is ([`sandjumper_flow::cone::comoving_cone`]) on the side view of the grains
//!   ([`SideView`]): over the frames with the paper's added mass, the down speed over the
//!   foot's averaged in the foot's frame; on each side the edge where it falls below one
//!   half; the sides' lines give the cone's angle to the horizontal (the paper: about 60
//!   degrees).

use serde::{Deserialize, Serialize};

use crate::bed::GRAIN;
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
    /// What the measured half foot's momentum and force are multiplied by to be the full
    /// foot's: 2 against a sidewall, else 1.
    #[serde(default = "one")]
    pub symmetry_factor: f64,
}

fn one() -> f64 {
    1.0
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
    /// The column's momentum as LAMMPS measured it at this step (`column.txt`: regions that
    /// move with the foot, `compute reduce/region`; NaN for a run without it), kg m/s.
    pub momentum_under_foot_lammps_kg_m_s: f64,
    /// The paper's added mass `P / v_foot` (NaN while the foot is slower than the rule
    /// allows), kg.
    pub added_mass_kg: f64,
    /// Eq. 6 at this depth for this foot (C scaled by (R / 38 mm)^2), kg.
    pub eq6_added_mass_kg: f64,
}

/// One row of `force_depth.csv`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ForceRow {
    /// The window's mean time (its middle), s.
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
    let (p, ring) = (g.symmetry_factor * p, g.symmetry_factor * ring);
    Ok(FlowRow {
        t_s: frame.step as f64 * g.time_step_s,
        depth_m: g.surface_m - bottom,
        foot_speed_m_s: v_foot,
        momentum_under_foot_kg_m_s: p,
        grains_under_foot: n,
        momentum_ring_kg_m_s: ring,
        momentum_under_foot_lammps_kg_m_s: f64::NAN,
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
    parse_force(&read_text(path)?, &path.display().to_string(), g, fp)
}

/// [`read_force`] of the file's text; `name` names it in errors.
pub fn parse_force(
    text: &str,
    name: &str,
    g: &Geometry,
    fp: &dyn Fn(f64) -> Result<f64, String>,
) -> Result<Vec<ForceRow>, String> {
    let rows = parse_series(text, name, "step, time, force, lowest foot centre")?;
    rows.iter()
        .map(|f| {
            let depth = g.surface_m - (f[3] - g.foot_sphere_radius_m);
            Ok(ForceRow {
                t_s: f[1],
                depth_m: depth,
                force_n: g.symmetry_factor * f[2],
                model_penetration_force_n: fp(depth)?,
            })
        })
        .collect()
}

/// A file's text; the error names it.
fn read_text(path: &std::path::Path) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// The rows of a `fix ave/time` file of four columns (`what` names them for errors), its
/// `#` lines skipped. Errors name the file (`name`) and line.
fn parse_series(text: &str, name: &str, what: &str) -> Result<Vec<[f64; 4]>, String> {
    let mut rows = Vec::new();
    for (no, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let f: Vec<f64> = l
            .split_whitespace()
            .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| {
                format!(
                    "{name}:{}: `{l}` is not four finite numbers (a run that diverged writes nan)",
                    no + 1
                )
            })?;
        let whole = f.first().is_some_and(|s| *s >= 0.0 && s.fract() == 0.0);
        let row: [f64; 4] = f.try_into().ok().filter(|_| whole).ok_or_else(|| {
            format!(
                "{name}:{}: `{l}` (allowed: {what}; the file is cut short or not of this run)",
                no + 1
            )
        })?;
        rows.push(row);
    }
    Ok(rows)
}

/// One row of `column.txt`: the column under the foot as LAMMPS measured it at a dump step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColumnRow {
    /// The step.
    pub step: u64,
    /// Down momentum of the grains under the foot, kg m/s.
    pub momentum_kg_m_s: f64,
    /// How many grains.
    pub grains: u64,
    /// Down momentum of the grains in the ring `R < r <= 2R` below the foot, kg m/s.
    pub ring_kg_m_s: f64,
}

/// Read `column.txt` (`fix ave/time`: step, momentum, grains, ring). Errors name the file and
/// line.
pub fn read_column(path: &std::path::Path) -> Result<Vec<ColumnRow>, String> {
    parse_column(&read_text(path)?, &path.display().to_string())
}

/// [`read_column`] of the file's text; `name` names it in errors.
pub fn parse_column(text: &str, name: &str) -> Result<Vec<ColumnRow>, String> {
    let rows = parse_series(text, name, "step, momentum, grains, ring momentum")?;
    rows.iter()
        .map(|f| {
            if !(f[2] >= 0.0 && f[2].fract() == 0.0) {
                return Err(format!(
                    "{name}: {} grains at step {} (allowed: a count)",
                    f[2], f[0]
                ));
            }
            Ok(ColumnRow {
                step: f[0] as u64,
                momentum_kg_m_s: f[1],
                grains: f[2] as u64,
                ring_kg_m_s: f[3],
            })
        })
        .collect()
}

/// The jammed cone: [`sandjumper_flow::cone::comoving_cone`], the same measure as the 2-D
/// DEM's, on the side view of the 3-D grains ([`SideView`]).
pub type Cone = sandjumper_flow::cone::ShearBandCone;

/// The grains' vertical velocity seen from the side, frame by frame: every grain below the
/// surface within 1.5 R of the axis, at `x' = sign(dx) sqrt(dx^2 + dy^2)` (its distance
/// from the axis, on the side of the axis it lies: the whole bed folded onto the plane
/// through the axis, each half on its side), averaged in cells half a grain wide and high.
/// The frames with the paper's added mass go to the cone measure.
#[derive(Clone, Debug)]
pub struct SideView {
    xs: Vec<f64>,
    hs: Vec<f64>,
    fields: Vec<(Vec<f64>, f64, f64)>,
}

impl SideView {
    /// Cells half a grain wide out to 1.5 R each side, half a grain high from the floor to
    /// the surface.
    pub fn new(g: &Geometry) -> Self {
        let c = 0.5 * g.grain_diameter_m;
        let half = (1.5 * g.foot_radius_m / c).ceil() as i64;
        let xs = (-half..=half).map(|i| i as f64 * c).collect();
        let rows = (g.surface_m / c).ceil() as usize + 1;
        let hs = (0..rows).map(|j| j as f64 * c).collect();
        Self {
            xs,
            hs,
            fields: Vec::new(),
        }
    }

    /// Add a frame whose row has the paper's added mass.
    pub fn add(&mut self, frame: &Frame, g: &Geometry, row: &FlowRow) {
        let (nx, ny) = (self.xs.len(), self.hs.len());
        let c = 0.5 * g.grain_diameter_m;
        let half = (nx / 2) as f64;
        let mut sum = vec![0.0; nx * ny];
        let mut n = vec![0u32; nx * ny];
        for a in frame.atoms.iter().filter(|a| a.kind == GRAIN) {
            let (dx, dy) = (a.x[0] - g.axis_m.0, a.x[1] - g.axis_m.1);
            let x = dx.signum() * (dx * dx + dy * dy).sqrt();
            let i = (x / c + half).round();
            let j = (a.x[2] / c).round();
            if i < 0.0 || j < 0.0 || i as usize >= nx || j as usize >= ny {
                continue;
            }
            let k = j as usize * nx + i as usize;
            sum[k] += a.v[2];
            n[k] += 1;
        }
        let field = sum
            .iter()
            .zip(&n)
            .map(|(s, &n)| if n > 0 { s / f64::from(n) } else { f64::NAN })
            .collect();
        self.fields
            .push((field, g.surface_m - row.depth_m, row.foot_speed_m_s));
    }

    /// The cone of the frames added.
    pub fn cone(&self, g: &Geometry) -> Option<Cone> {
        let samples: Vec<sandjumper_flow::cone::MotionSample<'_>> = self
            .fields
            .iter()
            .map(|(f, bottom, v)| sandjumper_flow::cone::MotionSample {
                v_up_m_s: f,
                foot_bottom_m: *bottom,
                foot_speed_m_s: *v,
            })
            .collect();
        sandjumper_flow::cone::comoving_cone(&samples, &self.xs, &self.hs, g.foot_radius_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bed::FOOT;
    use crate::dump::DumpAtom;

    /// A diverged run's `nan` in LAMMPS's own measures is refused, naming the line.
    #[test]
    fn a_nan_in_force_or_column_is_refused() {
        let e = parse_column("# c\n0 0.1 3 0.0\n50 nan 3 0.0\n", "column.txt").unwrap_err();
        assert!(e.contains("column.txt:3") && e.contains("finite"), "{e}");
        let e = parse_force("50 0.1 inf 0.04\n", "force.txt", &geometry(), &|d| Ok(d)).unwrap_err();
        assert!(e.contains("force.txt:1") && e.contains("finite"), "{e}");
        assert_eq!(parse_column("0 0.1 3 0.0\n", "c").unwrap().len(), 1);
    }

    fn geometry() -> Geometry {
        Geometry {
            axis_m: (0.03, 0.03),
            symmetry_factor: 1.0,
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
        let mut view = SideView::new(&g);
        view.add(&frame, &g, &row);
        let cone = view.cone(&g).unwrap();
        assert!((cone.angle_deg - 60.0).abs() < 4.0, "{cone:?}");
        assert!(
            (cone.apex_depth_m - 0.01 * 60f64.to_radians().tan()).abs() < 0.002,
            "{}",
            cone.apex_depth_m
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
                momentum_under_foot_lammps_kg_m_s: f64::NAN,
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
