//! The folder a finished intrusion writes: data (CSV, `.npy`), pictures (PNG, SVG, GIF),
//! side-wall frames that `sandjumper piv` reads, the resolved parameters, and a summary with
//! the structure of the flow (crystallisation, the jammed region) and the added mass against
//! the model's eq. 6.

use std::path::Path;

use serde::Serialize;

use super::intrude::{FlowRow, Run};
use super::structure::{JammedRegion, hexatic_order, jammed_region};
use crate::error::DemError;
use sandjumper_flow::figure::MapFigure;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel};
use sandjumper_output::plot::{palette, save_figure};
use sandjumper_output::{StagedDir, write_csv, write_npy};

/// What a run reports.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Where it was written.
    pub out: String,
    /// Grains (free and intruder).
    pub grains: usize,
    /// Steps.
    pub steps: u64,
    /// Step, s.
    pub dt_s: f64,
    /// Shortest contact time, s.
    pub contact_time_s: f64,
    /// `t_c v / d` at the fastest intrusion speed.
    pub contact_time_speed_over_d: f64,
    /// `v / sqrt(g d)`.
    pub froude: f64,
    /// Deepest intrusion, m.
    pub max_depth_m: f64,
    /// Largest force on the intruder, N.
    pub max_force_n: f64,
    /// The paper's added mass (`P` under the foot over `v_foot`) at the last sample where the
    /// foot still moved at least the spec's share of its fastest speed, kg.
    pub final_added_mass_kg: f64,
    /// Median over those samples of the DEM's added mass over the model's eq. 6 at the same
    /// depth, with `C` scaled by `(R / 38 mm)^2` for this foot.
    pub added_mass_vs_eq6_median: f64,
    /// The headline comparison with eq. 6: the same ratio's median over the samples at the
    /// depths where eq. 6's cone is forming ([`Summary::cone_forming_depths_m`]; NaN: no
    /// sample there). Shallower samples set eq. 6 near zero against what the column carries
    /// from contact and inflate the all-samples median.
    pub added_mass_vs_eq6_cone_forming_median: f64,
    /// The depths of that median: from where eq. 6 reaches a quarter of its complete cone's
    /// value to where the cone completes (`R tan theta / mu`), m
    /// ([`sandjumper_flow::momentum::cone_forming_depths`]).
    pub cone_forming_depths_m: [f64; 2],
    /// Samples in that median.
    pub cone_forming_samples: usize,
    /// Largest momentum of the column under the foot (down positive), kg m/s.
    pub grain_momentum_under_foot_kg_m_s: f64,
    /// Median over the samples with the paper's added mass of the share of the column's
    /// momentum that lies deeper than the jammed cone (`R tan 60` under the foot): how much
    /// the measurement depends on the column's depth `H` (0: none).
    pub momentum_beyond_cone_depth_share: f64,
    /// Median over the same samples of the share of the column's momentum in the window's
    /// bottom tenth: above [`WINDOW_BOTTOM_SHARE_LIMIT`] the motion reaches the window's
    /// bottom and the added mass depends on the window's depth `H`.
    pub momentum_in_window_bottom_tenth_share: f64,
    /// Said when the motion reaches the window's bottom (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window_depth_warning: Option<String>,
    /// Hexatic order of the bed at the end (1: crystal).
    pub hexatic_order: f64,
    /// The jammed region under the intruder at the last intruding sample.
    pub jammed: JammedRegion,
    /// The jammed cone from the shear bands of the strain-rate field, averaged in the foot's
    /// frame over the samples where the added mass is taken (`null`: fewer than three rows
    /// show bands); its rows are in `cone.csv`.
    pub shear_band_cone: Option<sandjumper_flow::cone::ShearBandCone>,
    /// The jammed cone as the region moving down with the foot: the down speed over the
    /// foot's, averaged the same way, its edge where it falls below one half (the middle of
    /// the bands' velocity step); `null`: fewer than three rows narrower than the foot. Its
    /// rows are in `comoving_cone.csv`.
    pub comoving_cone: Option<sandjumper_flow::cone::ShearBandCone>,
    /// Samples.
    pub samples: usize,
    /// Side-wall frames written.
    pub frames: usize,
    /// Largest overlap over a radius at the end.
    pub max_overlap_ratio: f64,
    /// Stepping speed of this process (the steps since the start or the resume).
    pub performance: super::intrude::Performance,
}

impl Summary {
    /// What `dem intrude --json` prints: this summary as pretty JSON.
    pub fn json(&self) -> Result<String, DemError> {
        serde_json::to_string_pretty(self).map_err(DemError::internal)
    }

    /// One line for the terminal.
    pub fn line(&self) -> String {
        format!(
            "dem intrude: {} grains, {} steps, depth {:.2} mm, peak force {:.3} N, added mass {:.4} kg ({:.2}x the model's eq. 6 where its cone forms, {:.2}x over all samples), jammed region side {:.1} deg, hexatic order {:.2}; t_c v/d {:.2e}, Froude {:.2}; {:.1} M atom-steps/s; written to {}",
            self.grains,
            self.steps,
            1e3 * self.max_depth_m,
            self.max_force_n,
            self.final_added_mass_kg,
            self.added_mass_vs_eq6_cone_forming_median,
            self.added_mass_vs_eq6_median,
            self.jammed.side_angle_deg,
            self.hexatic_order,
            self.contact_time_speed_over_d,
            self.froude,
            1e-6 * self.performance.atom_steps_per_s,
            self.out
        )
    }
}

const FLOW_HEADER: &[&str] = &[
    "sample",
    "t_s",
    "depth_m",
    "foot_speed_m_s",
    "momentum_left_kg_m_s",
    "momentum_right_kg_m_s",
    "momentum_kg_m_s",
    "momentum_under_foot_kg_m_s",
    "momentum_under_foot_to_cone_depth_kg_m_s",
    "momentum_band_r_to_2r_kg_m_s",
    "momentum_band_2r_to_3r_kg_m_s",
    "momentum_elsewhere_kg_m_s",
    "momentum_in_window_bottom_tenth_kg_m_s",
    "added_mass_kg",
    "max_shear_rate_per_s",
    "cells",
];

/// TOML has no null: drop them (NaN numbers and absent options serialise as null in JSON).
fn strip_nulls(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|_, x| !x.is_null());
            m.values_mut().for_each(strip_nulls);
        }
        serde_json::Value::Array(a) => {
            a.retain(|x| !x.is_null());
            a.iter_mut().for_each(strip_nulls);
        }
        _ => {}
    }
}

fn err(e: impl std::fmt::Display) -> DemError {
    DemError::internal(e.to_string())
}

/// The model's sand (eq. 4, preset at `phi`) under a foot of radius `r_m`, for its
/// penetration force: its stiffnesses scale with the foot's area, as the model's do for any
/// foot, and so does eq. 6's `C` (as [`model_added_mass`] scales it).
fn model_sand(phi: f64, r_m: f64) -> Result<sandjumper_model::ground::Sand, String> {
    let mut params = sandjumper_model::params::Params::preset(phi).map_err(|e| e.to_string())?;
    let reference = params.sand.reference_foot_radius_m;
    params.sand.added_mass_c_m2 *= (r_m / reference).powi(2);
    params.robot.foot_radius_m = r_m;
    Ok(sandjumper_model::ground::Sand::new(
        &params,
        sandjumper_model::ground::GroundLaw::resolve(
            sandjumper_model::params::ModelName::Eq4,
            &params.model,
        ),
    ))
}

/// The model's added mass (eq. 6 preset at `phi`) for a foot of radius `r_m` at the episode
/// depth `depth_m`, kg (`C` scaled with the foot's area, as the stiffnesses are): the flow
/// crate's, which PIV's added mass is drawn beside.
pub use sandjumper_flow::momentum::model_added_mass;

/// The model's penetration force `F_p(z)` (eq. 4's cone law, preset at `phi`) for a foot of
/// radius `r_m` at depth `depth_m`, N.
pub fn model_penetration_force(phi: f64, r_m: f64, depth_m: f64) -> Result<f64, String> {
    Ok(model_sand(phi, r_m)?.penetration_force(depth_m))
}

/// Median DEM/eq. 6 added-mass ratio over the samples that have the paper's added mass
/// (finite: the foot moving fast enough), at their depth, for a foot of radius
/// `foot_radius_m`.
pub fn added_mass_vs_eq6_median(flow: &[FlowRow], phi: f64, foot_radius_m: f64) -> f64 {
    median(
        added_mass_vs_eq6_by_depth(flow, phi, foot_radius_m)
            .into_iter()
            .map(|(.., ratio)| ratio)
            .collect(),
    )
}

/// The DEM/eq. 6 ratio of each sample with the paper's added mass, as (depth, DEM's added
/// mass, eq. 6's, their ratio): the per-depth curve the headline median is taken from.
pub fn added_mass_vs_eq6_by_depth(
    flow: &[FlowRow],
    phi: f64,
    foot_radius_m: f64,
) -> Vec<(f64, f64, f64, f64)> {
    flow.iter()
        .filter(|r| r.depth_m > 0.0 && r.added_mass_kg.is_finite())
        .filter_map(|r| {
            let m = model_added_mass(phi, foot_radius_m, r.depth_m).ok()?;
            (m > 0.0).then(|| (r.depth_m, r.added_mass_kg, m, r.added_mass_kg / m))
        })
        .collect()
}

/// The headline DEM/eq. 6 ratio: its median over the samples at the depths where eq. 6's cone
/// is forming, with those depths (m) and the samples counted.
pub fn added_mass_vs_eq6_cone_forming(
    flow: &[FlowRow],
    phi: f64,
    foot_radius_m: f64,
) -> (f64, [f64; 2], usize) {
    let Ok((from, to)) = sandjumper_flow::momentum::cone_forming_depths(phi, foot_radius_m) else {
        return (f64::NAN, [f64::NAN; 2], 0);
    };
    let ratios: Vec<f64> = added_mass_vs_eq6_by_depth(flow, phi, foot_radius_m)
        .into_iter()
        .filter(|&(d, ..)| (from..=to).contains(&d))
        .map(|(.., ratio)| ratio)
        .collect();
    let n = ratios.len();
    (median(ratios), [from, to], n)
}

/// The middle value (the upper one of an even count), NaN for none.
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Above this share of the column's momentum in the window's bottom tenth, the summary warns
/// that the window is too shallow.
pub const WINDOW_BOTTOM_SHARE_LIMIT: f64 = 0.05;

/// Median over the samples with the paper's added mass of the share of the column's momentum
/// in the window's bottom tenth.
fn bottom_share(flow: &[FlowRow]) -> f64 {
    median(
        flow.iter()
            .filter(|r| r.added_mass_kg.is_finite() && r.momentum_under_foot_kg_m_s > 0.0)
            .map(|r| r.momentum_in_window_bottom_tenth_kg_m_s / r.momentum_under_foot_kg_m_s)
            .collect(),
    )
}

/// Median over the samples with the paper's added mass of the share of the column's momentum
/// deeper than the jammed cone.
fn beyond_cone_share(flow: &[FlowRow]) -> f64 {
    median(
        flow.iter()
            .filter(|r| r.added_mass_kg.is_finite() && r.momentum_under_foot_kg_m_s > 0.0)
            .map(|r| {
                1.0 - r.momentum_under_foot_to_cone_depth_kg_m_s / r.momentum_under_foot_kg_m_s
            })
            .collect(),
    )
}

/// Write the finished run into `out` (from the work directory `work`, removed after).
pub fn write(run: &Run, work: &Path, out: &Path) -> Result<Summary, DemError> {
    let staged = StagedDir::create(out)?;
    let spec = &run.spec;
    let grid = &run.grid;
    write_csv(
        &staged.file("force_depth.csv"),
        &run.state.force,
        &["t_s", "depth_m", "velocity_m_s", "force_n"],
    )
    .map_err(err)?;
    write_csv(&staged.file("flow.csv"), &run.state.flow, FLOW_HEADER).map_err(err)?;
    #[derive(Serialize)]
    struct Am {
        depth_m: f64,
        added_mass_kg: f64,
    }
    let am: Vec<Am> = run
        .state
        .flow
        .iter()
        .filter(|r| r.depth_m > 0.0 && r.foot_speed_m_s > 0.0 && r.added_mass_kg.is_finite())
        .map(|r| Am {
            depth_m: r.depth_m,
            added_mass_kg: r.added_mass_kg,
        })
        .collect();
    write_csv(
        &staged.file("added_mass.csv"),
        &am,
        &["depth_m", "added_mass_kg"],
    )
    .map_err(err)?;
    // Fields: per sample CSV, and stacked arrays (samples, rows, columns).
    std::fs::create_dir_all(staged.file("fields")).map_err(err)?;
    let (nx, ny) = (grid.nx, grid.ny);
    let xs: Vec<f64> = (0..nx).map(|i| grid.node(i, 0).0).collect();
    let hs: Vec<f64> = (0..ny)
        .map(|j| grid.node(0, j).1 - spec.surface_m)
        .collect();
    let axis_x = 0.5 * (spec.bed_x_m.0 + spec.bed_x_m.1);
    let xs_axis: Vec<f64> = xs.iter().map(|x| x - axis_x).collect();
    let cone = shear_band_cone(run, &xs_axis, &hs);
    let comoving_cone = comoving_cone(run, &xs_axis, &hs);
    for (c, name) in [(&cone, "cone.csv"), (&comoving_cone, "comoving_cone.csv")] {
        if let Some(c) = c {
            write_csv(
                &staged.file(name),
                &c.rows,
                &["depth_below_foot_m", "left_m", "right_m", "contrast"],
            )
            .map_err(err)?;
        }
    }
    for (k, f) in run.fields.iter().enumerate() {
        #[derive(Serialize)]
        struct Cell {
            x_m: f64,
            h_m: f64,
            u_m_s: f64,
            v_m_s: f64,
            shear_rate_per_s: f64,
            vorticity_per_s: f64,
        }
        let rows: Vec<Cell> = (0..nx * ny)
            .map(|c| Cell {
                x_m: xs[c % nx] - 0.5 * (spec.bed_x_m.0 + spec.bed_x_m.1),
                h_m: hs[c / nx],
                u_m_s: f[0][c],
                v_m_s: f[1][c],
                shear_rate_per_s: f[2][c],
                vorticity_per_s: f[3][c],
            })
            .collect();
        write_csv(&staged.file(&format!("fields/{k:04}.csv")), &rows, &[]).map_err(err)?;
    }
    let ns = run.fields.len() as u64;
    let shape = [ns, ny as u64, nx as u64];
    let axis = 0.5 * (spec.bed_x_m.0 + spec.bed_x_m.1);
    write_npy(
        &staged.file("x_m.npy"),
        &[nx as u64],
        xs.iter().map(|x| x - axis).collect(),
    )
    .map_err(err)?;
    write_npy(&staged.file("h_m.npy"), &[ny as u64], hs.clone()).map_err(err)?;
    for (q, name) in ["u_m_s", "v_m_s", "shear_rate_per_s", "vorticity_per_s"]
        .iter()
        .enumerate()
    {
        write_npy(
            &staged.file(&format!("{name}.npy")),
            &shape,
            run.fields
                .iter()
                .flat_map(|f| f[q].iter().copied())
                .collect(),
        )
        .map_err(err)?;
    }
    // Side-wall frames with the foot outline per frame and the camera for `piv`.
    let cam = run.camera;
    let mut frames = 0;
    if spec.frames {
        std::fs::rename(work.join("frames"), staged.file("frames")).map_err(err)?;
        frames = run.state.flow.len();
        #[derive(Serialize)]
        struct Foot {
            frame: u64,
            x_px: f64,
            y_px: f64,
        }
        let (l, r) = spec.intruder().edges();
        let mut foot = Vec::new();
        for row in &run.state.flow {
            let bottom = spec.surface_m - row.depth_m;
            let (xl, yb) = cam.to_px(l, bottom);
            let (xr, _) = cam.to_px(r, bottom);
            for (x, y) in [(xl, -1.0), (xr, -1.0), (xr, yb), (xl, yb)] {
                foot.push(Foot {
                    frame: row.sample,
                    x_px: x,
                    y_px: y,
                });
            }
        }
        write_csv(&staged.file("foot.csv"), &foot, &["frame", "x_px", "y_px"]).map_err(err)?;
    }
    let (ox, oy) = cam.to_px(axis, spec.surface_m);
    staged
        .write_text(
            "camera.toml",
            &format!(
                "# The virtual side-wall camera of frames/; `sandjumper piv` on them:\n# sandjumper piv frames --m-per-px {} --fps {} --origin {ox:.3},{oy:.3} --foot foot.csv --phi {}\nm_per_px = {}\nfps = {}\norigin_px = [{ox}, {oy}]\nwidth_px = {}\nheight_px = {}\nleft_m = {}\ntop_m = {}\n",
                cam.m_per_px, spec.fps, spec.phi_bulk, cam.m_per_px, spec.fps, cam.width_px, cam.height_px, cam.left_m, cam.top_m
            ),
        )
        .map_err(err)?;
    // Animation from the snapshots.
    let mut gif_frames = Vec::new();
    for k in 0..run.state.flow.len() {
        let p = work.join(format!("snapshots/{k:06}.png"));
        let img = image::open(&p)
            .map_err(|e| DemError::internal(format!("cannot read {}: {e}", p.display())))?;
        gif_frames.push(img.to_rgba8());
    }
    sandjumper_flow::figure::write_gif(&staged.file("animation.gif"), gif_frames, 100)
        .map_err(DemError::internal)?;
    // Structure and summary.
    let p = spec.params;
    let last = run
        .state
        .flow
        .iter()
        .rev()
        .find(|r| r.foot_speed_m_s > 0.0 && r.depth_m > 0.0)
        .copied();
    let intr = spec.intruder();
    let jammed = match last {
        Some(r) => jammed_region(
            &run.world,
            intr.x_centre_m,
            0.5 * spec.foot_width_m,
            spec.surface_m - run.spec.trajectory().depth(run.world.t_s),
            r.foot_speed_m_s,
            0.5,
            p.diameter_m * p.sizes.max_factor(),
        ),
        None => jammed_region(
            &run.world,
            intr.x_centre_m,
            0.5 * spec.foot_width_m,
            0.0,
            1.0,
            2.0,
            p.diameter_m,
        ),
    };
    let hex = hexatic_order(&run.world);
    let dl = p.dimensionless(spec.trajectory().max_speed());
    let ratio = added_mass_vs_eq6_median(&run.state.flow, spec.phi_bulk, 0.5 * spec.foot_width_m);
    let (forming, forming_depths, forming_samples) =
        added_mass_vs_eq6_cone_forming(&run.state.flow, spec.phi_bulk, 0.5 * spec.foot_width_m);
    let bottom_share = bottom_share(&run.state.flow);
    let summary = Summary {
        out: out.display().to_string(),
        grains: run.world.g.len(),
        steps: run.world.steps,
        dt_s: p.dt_s,
        contact_time_s: dl.contact_time_s,
        contact_time_speed_over_d: dl.contact_time_speed_over_d,
        froude: dl.froude,
        max_depth_m: spec.depth_m.iter().copied().fold(f64::MIN, f64::max),
        max_force_n: run
            .state
            .force
            .iter()
            .map(|r| r.force_n)
            .fold(0.0, f64::max),
        final_added_mass_kg: run
            .state
            .flow
            .iter()
            .rev()
            .find(|r| r.added_mass_kg.is_finite())
            .map_or(f64::NAN, |r| r.added_mass_kg),
        added_mass_vs_eq6_median: ratio,
        added_mass_vs_eq6_cone_forming_median: forming,
        cone_forming_depths_m: forming_depths,
        cone_forming_samples: forming_samples,
        momentum_beyond_cone_depth_share: beyond_cone_share(&run.state.flow),
        momentum_in_window_bottom_tenth_share: bottom_share,
        window_depth_warning: (bottom_share > WINDOW_BOTTOM_SHARE_LIMIT).then(|| {
            format!(
                "{:.1} % of the column's momentum is in the window's bottom tenth: the motion reaches the window's bottom, so the added mass depends on its depth (make the bed deeper)",
                100.0 * bottom_share
            )
        }),
        grain_momentum_under_foot_kg_m_s: run
            .state
            .flow
            .iter()
            .map(|r| r.momentum_under_foot_kg_m_s)
            .fold(f64::NAN, f64::max),
        hexatic_order: hex,
        jammed,
        shear_band_cone: cone,
        comoving_cone,
        samples: run.state.flow.len(),
        frames,
        performance: run.performance,
        max_overlap_ratio: run.world.max_overlap_ratio(),
    };
    #[derive(Serialize)]
    struct Record<'a> {
        summary: &'a Summary,
        spec: &'a super::intrude::IntrudeSpec,
        grid: &'a super::coarse::GridSpec,
        camera: &'a super::render::SideCamera,
    }
    let rec = Record {
        summary: &summary,
        spec,
        grid,
        camera: &cam,
    };
    let mut toml_rec = serde_json::to_value(&rec).map_err(err)?;
    // TOML has no NaN-free guarantee from JSON; trajectories are long: keep them in JSON only.
    if let Some(s) = toml_rec.get_mut("spec").and_then(|s| s.as_object_mut()) {
        s.remove("t_s");
        s.remove("depth_m");
    }
    strip_nulls(&mut toml_rec);
    staged
        .write_text("dem.toml", &toml::to_string(&toml_rec).map_err(err)?)
        .map_err(DemError::from)?;
    staged
        .write_text(
            "summary.json",
            &serde_json::to_string_pretty(&rec).map_err(err)?,
        )
        .map_err(DemError::from)?;
    // Figures: force and added mass against depth, the last shear map, a snapshot.
    let force_fig = LineFigure {
        title: "DEM: force of the grains on the intruder".into(),
        panels: vec![LinePanel {
            caption: format!(
                "{:?} model, foot {:.1} mm",
                p.model,
                1e3 * spec.foot_width_m
            ),
            x_desc: "depth (mm)".into(),
            y_desc: "force (N)".into(),
            lines: vec![Line {
                label: "DEM".into(),
                points: run
                    .state
                    .force
                    .iter()
                    .map(|r| (1e3 * r.depth_m, r.force_n))
                    .collect(),
                color: palette(0),
                dashed: false,
                markers: false,
            }],
            y_from_zero: false,
        }],
        size: (900, 600),
    };
    save_figure(
        &force_fig,
        &staged.file("force_depth.png"),
        Some(&staged.file("force_depth.svg")),
    )?;
    let zmax = am.iter().map(|r| r.depth_m).fold(0.0, f64::max).max(1e-4);
    let model: Vec<(f64, f64)> = (0..=60)
        .filter_map(|i| {
            let z = zmax * f64::from(i) / 60.0;
            model_added_mass(spec.phi_bulk, 0.5 * spec.foot_width_m, z)
                .ok()
                .map(|m| (1e3 * z, m))
        })
        .collect();
    let am_fig = LineFigure {
        title: "DEM added mass P / v_foot against depth, and the model's eq. 6".into(),
        panels: vec![LinePanel {
            caption: format!(
                "phi {} (rho phi for P), foot {:.1} mm",
                spec.phi_bulk,
                1e3 * spec.foot_width_m
            ),
            x_desc: "depth (mm)".into(),
            y_desc: "added mass (kg)".into(),
            lines: vec![
                Line {
                    label: "DEM: P under the foot / v_foot (v >= share of v_max)".into(),
                    points: am
                        .iter()
                        .map(|r| (1e3 * r.depth_m, r.added_mass_kg))
                        .collect(),
                    color: palette(0),
                    dashed: false,
                    markers: true,
                },
                Line {
                    label: "eq. 6 (preset), C scaled with R^2".into(),
                    points: model,
                    color: palette(1),
                    dashed: true,
                    markers: false,
                },
            ],
            y_from_zero: true,
        }],
        size: (900, 600),
    };
    save_figure(
        &am_fig,
        &staged.file("added_mass.png"),
        Some(&staged.file("added_mass.svg")),
    )?;
    if let (Some(f), Some(r)) = (run.fields.last(), run.state.flow.last()) {
        let (fl, fr) = intr.edges();
        let px = super::coarse::PX_PER_NODE as f64;
        let to_px = |x: f64, y: f64| {
            (
                (x - (grid.x0_m - 0.5 * grid.spacing_m)) / grid.spacing_m * px,
                ((grid.top_m + 0.5 * grid.spacing_m) - y) / grid.spacing_m * px,
            )
        };
        let bottom = spec.surface_m - r.depth_m;
        let outline = vec![
            to_px(fl, bottom),
            to_px(fr, bottom),
            to_px(fr, grid.top_m),
            to_px(fl, grid.top_m),
        ];
        let fig = MapFigure {
            title: format!(
                "DEM max shear strain rate (eq. 2) at depth {:.1} mm",
                1e3 * r.depth_m
            ),
            label: "shear rate (1/s)".into(),
            image: (
                nx * super::coarse::PX_PER_NODE,
                ny * super::coarse::PX_PER_NODE,
            ),
            xs: (0..nx).map(|i| (i as f64 + 0.5) * px).collect(),
            ys: (0..ny).map(|j| (j as f64 + 0.5) * px).collect(),
            values: f[2].clone(),
            arrows: Vec::new(),
            outlines: vec![outline],
        };
        save_figure(
            &fig,
            &staged.file("shear_rate.png"),
            Some(&staged.file("shear_rate.svg")),
        )?;
    }
    super::figure::save_snapshot(
        &run.world,
        &cam,
        spec.trajectory().max_speed().max(1e-3),
        &format!(
            "DEM at t = {:.1} ms, grains coloured by speed",
            1e3 * run.world.t_s
        ),
        &staged.file("snapshot.png"),
        &staged.file("snapshot.svg"),
    )?;
    let target = staged.commit()?;
    sandjumper_output::remove_work_dir(work);
    Ok(Summary {
        out: target.display().to_string(),
        ..summary
    })
}

/// The samples of `run` whose added mass is taken (the foot in the bed, intruding at least the
/// speed threshold), with their fields: what both cone measures average.
fn with_added_mass(run: &Run) -> impl Iterator<Item = (&FlowRow, &[Vec<f64>; 4])> {
    run.state
        .flow
        .iter()
        .zip(&run.fields)
        .filter(|(r, _)| r.added_mass_kg.is_finite() && r.depth_m > 0.0)
}

/// The shear-band cone of `run` ([`sandjumper_flow::cone`]): the shear-rate fields of the
/// samples whose added mass is taken (the foot intruding at least the speed threshold), on
/// the grid's columns `xs` (from the foot's axis) and rows `hs` (from the surface, up).
fn shear_band_cone(
    run: &Run,
    xs: &[f64],
    hs: &[f64],
) -> Option<sandjumper_flow::cone::ShearBandCone> {
    let samples: Vec<sandjumper_flow::cone::Sample<'_>> = with_added_mass(run)
        .map(|(r, f)| sandjumper_flow::cone::Sample {
            shear_rate: &f[2],
            foot_bottom_m: -r.depth_m,
        })
        .collect();
    sandjumper_flow::cone::shear_band_cone(&samples, xs, hs, 0.5 * run.spec.foot_width_m)
}

/// The co-moving cone of `run` ([`sandjumper_flow::cone::comoving_cone`]) from the vertical
/// velocity fields of the same samples as [`shear_band_cone`].
fn comoving_cone(
    run: &Run,
    xs: &[f64],
    hs: &[f64],
) -> Option<sandjumper_flow::cone::ShearBandCone> {
    let samples: Vec<sandjumper_flow::cone::MotionSample<'_>> = with_added_mass(run)
        .map(|(r, f)| sandjumper_flow::cone::MotionSample {
            v_up_m_s: &f[1],
            foot_bottom_m: -r.depth_m,
            foot_speed_m_s: r.foot_speed_m_s,
        })
        .collect();
    sandjumper_flow::cone::comoving_cone(&samples, xs, hs, 0.5 * run.spec.foot_width_m)
}

#[cfg(test)]
mod tests {
    use super::model_added_mass;

    #[test]
    fn eq6_scales_its_area_c_with_the_foot_radius_squared() {
        // The paper's foot: the preset as it is.
        let big = model_added_mass(0.57, 0.038, 0.01).unwrap();
        let params = sandjumper_model::params::Params::preset(0.57).unwrap();
        let sand = sandjumper_model::ground::Sand::new(
            &params,
            sandjumper_model::ground::GroundLaw::resolve(
                sandjumper_model::params::ModelName::Eq4,
                &params.model,
            ),
        );
        assert!((big - sand.added_mass(0.01)).abs() < 1e-12 * big);
        // Half the radius, a shallow depth where the cone is a frustum of the same shape:
        // every term of eq. 6 scales with R^2 only if C does.
        let s = 0.0005;
        let (m1, m2) = (
            model_added_mass(0.57, 0.038, s).unwrap(),
            model_added_mass(0.57, 0.019, 0.5 * s).unwrap(),
        );
        assert!(
            (m2 / m1 - 0.125).abs() < 1e-9,
            "R^3 scaling at similar depths: {}",
            m2 / m1
        );
    }

    #[test]
    fn the_headline_ratio_is_taken_where_eq6_cone_forms_only() {
        use super::{FlowRow, added_mass_vs_eq6_cone_forming, added_mass_vs_eq6_median};
        let (phi, r) = (0.57, 0.038);
        let (from, to) = sandjumper_flow::momentum::cone_forming_depths(phi, r).unwrap();
        // A column carrying twice eq. 6 where the cone forms, plus a contact offset that makes
        // the shallow samples' ratios huge, and samples past the cone's completion at 1x.
        let row = |depth_m: f64, added_mass_kg: f64| FlowRow {
            sample: 0,
            t_s: 0.0,
            depth_m,
            foot_speed_m_s: 1.0,
            momentum_left_kg_m_s: 0.0,
            momentum_right_kg_m_s: 0.0,
            momentum_kg_m_s: 0.0,
            momentum_under_foot_kg_m_s: 0.0,
            momentum_under_foot_to_cone_depth_kg_m_s: 0.0,
            momentum_band_r_to_2r_kg_m_s: 0.0,
            momentum_band_2r_to_3r_kg_m_s: 0.0,
            momentum_elsewhere_kg_m_s: 0.0,
            momentum_in_window_bottom_tenth_kg_m_s: 0.0,
            added_mass_kg,
            max_shear_rate_per_s: 0.0,
            cells: 0,
        };
        let eq6 = |d: f64| model_added_mass(phi, r, d).unwrap();
        let mut flow = Vec::new();
        for k in 1..=8 {
            let d = 0.1 * from * f64::from(k);
            flow.push(row(d, eq6(d) + 0.05));
        }
        for k in 0..=4 {
            let d = from + (to - from) * f64::from(k) / 4.0;
            flow.push(row(d, 2.0 * eq6(d)));
        }
        for k in 1..=3 {
            let d = to * (1.0 + 0.1 * f64::from(k));
            flow.push(row(d, eq6(d)));
        }
        // A sample the speed rule drops.
        flow.push(row(0.5 * (from + to), f64::NAN));
        let (headline, depths, n) = added_mass_vs_eq6_cone_forming(&flow, phi, r);
        assert_eq!(n, 5);
        assert_eq!(depths, [from, to]);
        assert!((headline - 2.0).abs() < 1e-12, "{headline}");
        // Over all samples the shallow ones pull the median up.
        let all = added_mass_vs_eq6_median(&flow, phi, r);
        assert!(all > 2.0, "{all}");
    }
}
