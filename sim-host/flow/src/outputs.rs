//! The output folder of a PIV run ([`PivOutcome::write`]): the animation, the per-pair
//! field tables, the stacked `.npy` arrays, `flow.csv` and `added_mass.csv`, `piv.toml`, the
//! maps, the added-mass figure and `summary.json`.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::analysis::{
    FLOW_HEADER, FlowRow, Frames, PairResult, Pairing, PivOptions, PivRun, SiFields,
};
use crate::error::FlowError;
use crate::figure::MapFigure;
use crate::momentum::{Calibration, Polygon, model_added_mass};
use crate::piv::{PivConfig, VectorField};
use crate::preprocess::Preprocess;
use crate::run::{PivOutcome, PivRequest};
use sandjumper_output::StagedDir;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::{palette, save_figure};

impl PivOutcome {
    /// Write the output folder `dir` atomically (it appears complete or not at all; an
    /// existing folder is replaced only if sandjumper wrote it) and return its path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, FlowError> {
        self.write_into(StagedDir::create(dir)?)
    }

    /// Write the folder already claimed as `staged` and commit it; its path.
    pub fn write_into(&self, staged: StagedDir) -> Result<PathBuf, FlowError> {
        let (frames, run, opts) = (&self.frames, &self.run, &self.options);
        write_animation(&staged, frames, run)?;
        write_field_tables(&staged, run, opts.calibration)?;
        write_arrays(&staged, run)?;
        let added_mass = run.added_mass_points();
        write_tables(&staged, &self.flow, &added_mass)?;
        write_settings(&staged, &self.request, opts)?;
        write_maps(&staged, frames.size(), run, &self.flow, opts.feet.as_ref())?;
        if !added_mass.is_empty() {
            let radius_m = PivRun::foot_radius_m(opts).unwrap_or(f64::NAN);
            write_added_mass_figure(&staged, self.request.phi, radius_m, &added_mass)?;
        }
        staged.write_text("summary.json", &format!("{}\n", self.summary_json()?))?;
        Ok(staged.commit()?)
    }
}

fn csv_num(v: f64) -> String {
    if v.is_finite() {
        v.to_string()
    } else {
        String::new()
    }
}

/// `animation.gif` (the paper's Supplementary Video 2): each pair's frame A with its vectors,
/// at most 200 frames, 100 ms each.
fn write_animation(staged: &StagedDir, frames: &Frames, run: &PivRun) -> Result<(), FlowError> {
    let f0 = &run.results[0].field;
    let stride = (f0.nx / 40).max(1);
    let max_disp = run
        .results
        .iter()
        .flat_map(|r| r.field.u.iter().zip(&r.field.v).map(|(a, b)| a.hypot(*b)))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let scale = if max_disp > 0.0 {
        1.5 * (stride * f0.step_px) as f64 / max_disp
    } else {
        1.0
    };
    let gif: Vec<image::RgbaImage> = run
        .pairs
        .iter()
        .zip(&run.results)
        .take(200)
        .map(|(&(ia, _), r)| {
            crate::figure::animation_frame(&frames.images[ia], &r.field, stride, scale)
        })
        .collect();
    crate::figure::write_gif(&staged.file("animation.gif"), gif, 100).map_err(FlowError::internal)
}

/// `fields/NNNN.csv`: one table per pair, every vector with its flag and peak ratio, and in
/// SI units when calibrated.
fn write_field_tables(
    staged: &StagedDir,
    run: &PivRun,
    cal: Option<Calibration>,
) -> Result<(), FlowError> {
    let dir = staged.file("fields");
    std::fs::create_dir_all(&dir).map_err(FlowError::internal)?;
    for (k, PairResult { field: f, si, .. }) in run.results.iter().enumerate() {
        let mut wtr =
            csv::Writer::from_path(dir.join(format!("{k:04}.csv"))).map_err(FlowError::internal)?;
        let mut header = vec!["x_px", "y_px", "u_px", "v_px", "flag", "s2n"];
        if si.is_some() {
            header.extend([
                "x_m",
                "h_m",
                "u_m_s",
                "v_m_s",
                "vorticity_1_s",
                "shear_rate_1_s",
            ]);
        }
        wtr.write_record(&header).map_err(FlowError::internal)?;
        for j in 0..f.ny {
            for i in 0..f.nx {
                let q = j * f.nx + i;
                let mut rec = vec![
                    f.xs[i].to_string(),
                    f.ys[j].to_string(),
                    csv_num(f.u[q]),
                    csv_num(f.v[q]),
                    f.flag[q].to_string(),
                    csv_num(f.peak_ratio[q]),
                ];
                if let (Some(s), Some(c)) = (si, cal) {
                    rec.extend([
                        c.x_m(f.xs[i]).to_string(),
                        c.h_m(f.ys[j]).to_string(),
                        csv_num(s.u.values[q]),
                        csv_num(s.v.values[q]),
                        csv_num(s.vorticity.values[q]),
                        csv_num(s.shear_rate.values[q]),
                    ]);
                }
                wtr.write_record(&rec).map_err(FlowError::internal)?;
            }
        }
        wtr.flush().map_err(FlowError::internal)?;
    }
    Ok(())
}

/// One array of a PIV run for numpy: its name (the `.npy` file's stem), shape and values in
/// row-major order.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedArray {
    /// `u_px`, `v_px`, `flag`, `s2n`, `x_px`, `y_px`, and with a scale `u_m_s`, `v_m_s`,
    /// `vorticity_1_s`, `shear_rate_1_s`.
    pub name: &'static str,
    /// `(pairs, rows, columns)` for the fields, `(columns,)` and `(rows,)` for the grid.
    pub shape: Vec<u64>,
    /// Values, row-major.
    pub values: Vec<f64>,
}

/// The stacked arrays of `run` for numpy, `(pairs, rows, columns)`: the grid (px), the
/// displacements (px per pair), flags and peak ratios, and the SI fields when every pair has
/// them (what `piv --out` writes as `.npy` files, and the Python module returns in memory).
pub fn arrays(run: &PivRun) -> Vec<NamedArray> {
    let Some(first) = run.results.first() else {
        return Vec::new();
    };
    let f0 = &first.field;
    let (nx, ny, np) = (f0.nx as u64, f0.ny as u64, run.results.len() as u64);
    let field = |name, values| NamedArray {
        name,
        shape: vec![np, ny, nx],
        values,
    };
    let stack = |get: &dyn Fn(&VectorField) -> Vec<f64>| -> Vec<f64> {
        run.results.iter().flat_map(|r| get(&r.field)).collect()
    };
    let mut out = vec![
        NamedArray {
            name: "x_px",
            shape: vec![nx],
            values: f0.xs.clone(),
        },
        NamedArray {
            name: "y_px",
            shape: vec![ny],
            values: f0.ys.clone(),
        },
        field("u_px", stack(&|f| f.u.clone())),
        field("v_px", stack(&|f| f.v.clone())),
        field(
            "flag",
            stack(&|f| f.flag.iter().map(|&x| f64::from(x)).collect()),
        ),
        field("s2n", stack(&|f| f.peak_ratio.clone())),
    ];
    let si: Vec<&SiFields> = run.results.iter().filter_map(|r| r.si.as_ref()).collect();
    if si.len() == run.results.len() {
        let pick = |get: &dyn Fn(&SiFields) -> &Vec<f64>| -> Vec<f64> {
            si.iter().flat_map(|s| get(s).iter().copied()).collect()
        };
        out.push(field("u_m_s", pick(&|s| &s.u.values)));
        out.push(field("v_m_s", pick(&|s| &s.v.values)));
        out.push(field("vorticity_1_s", pick(&|s| &s.vorticity.values)));
        out.push(field("shear_rate_1_s", pick(&|s| &s.shear_rate.values)));
    }
    out
}

/// The stacked arrays for numpy ([`arrays`]), one `.npy` file each.
fn write_arrays(staged: &StagedDir, run: &PivRun) -> Result<(), FlowError> {
    for a in arrays(run) {
        sandjumper_output::write_npy(&staged.file(&format!("{}.npy", a.name)), &a.shape, a.values)
            .map_err(FlowError::internal)?;
    }
    Ok(())
}

/// `flow.csv` (one row per pair) and `added_mass.csv` (the table `fit added-mass` reads:
/// intruding pairs, depth increasing).
fn write_tables(
    staged: &StagedDir,
    rows: &[FlowRow],
    added_mass: &[(f64, f64)],
) -> Result<(), FlowError> {
    sandjumper_output::write_csv(&staged.file("flow.csv"), rows, &FLOW_HEADER)
        .map_err(FlowError::internal)?;
    let mut am = String::from("depth_m,added_mass_kg\n");
    for (z, m) in added_mass {
        am += &format!("{z},{m}\n");
    }
    staged.write_text("added_mass.csv", &am)?;
    Ok(())
}

/// `piv.toml`: the resolved settings of the run, enough to run it again.
#[derive(Debug, Serialize)]
struct PivSettings<'a> {
    /// The frames.
    frames: &'a str,
    /// Frame rate, frames/s (absent: timed by `log`, or not timed).
    #[serde(skip_serializing_if = "Option::is_none")]
    fps: Option<f64>,
    /// Acquisition log timing the frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    log: Option<String>,
    /// Static mask image.
    #[serde(skip_serializing_if = "Option::is_none")]
    mask: Option<String>,
    /// The foot's outlines.
    #[serde(skip_serializing_if = "Option::is_none")]
    foot: Option<String>,
    /// How frames are paired.
    pairs: Pairing,
    /// Every Nth pair analysed.
    every: usize,
    /// Packing fraction of the bed.
    phi: f64,
    /// Grain density, kg/m^3.
    grain_density_kg_m3: f64,
    /// Pixels to metres and the foot's axis at the surface.
    #[serde(skip_serializing_if = "Option::is_none")]
    calibration: Option<Calibration>,
    /// The correlation passes.
    piv: &'a PivConfig,
    /// Pre-processing.
    preprocess: &'a Preprocess,
}

fn write_settings(staged: &StagedDir, a: &PivRequest, opts: &PivOptions) -> Result<(), FlowError> {
    let shown = |p: &Option<PathBuf>| p.as_ref().map(|p| p.display().to_string());
    let settings = PivSettings {
        frames: &a.frames,
        fps: a.fps,
        log: shown(&a.log),
        mask: shown(&a.mask),
        foot: shown(&a.foot),
        pairs: opts.pairing,
        every: opts.every,
        phi: a.phi,
        grain_density_kg_m3: a.grain_density_kg_m3,
        calibration: opts.calibration,
        piv: &opts.piv,
        preprocess: &opts.preprocess,
    };
    let text = toml::to_string(&settings).map_err(FlowError::internal)?;
    staged.write_text(
        "piv.toml",
        &format!(
            "# sandjumper piv {}: the resolved settings\n{text}",
            a.frames
        ),
    )?;
    Ok(())
}

/// `speed.png/svg` and `shear_rate.png/svg`: the maps of the pair with the largest momentum
/// (or the middle pair), with the foot's outline.
fn write_maps(
    staged: &StagedDir,
    size: (usize, usize),
    run: &PivRun,
    rows: &[FlowRow],
    feet: Option<&std::collections::BTreeMap<u64, Polygon>>,
) -> Result<(), FlowError> {
    let pick = rows
        .iter()
        .enumerate()
        .filter(|(_, r)| r.momentum_kg_m_s.is_finite())
        .max_by(|x, y| {
            x.1.momentum_kg_m_s
                .abs()
                .total_cmp(&y.1.momentum_kg_m_s.abs())
        })
        .map_or(run.results.len() / 2, |(k, _)| k);
    let PairResult { field: f, si, .. } = &run.results[pick];
    let outlines: Vec<Vec<(f64, f64)>> = feet
        .and_then(|m| m.get(&rows[pick].frame_a))
        .cloned()
        .into_iter()
        .collect();
    let speed: Vec<f64> = match si {
        Some(s) => {
            s.u.values
                .iter()
                .zip(&s.v.values)
                .map(|(a, b)| a.hypot(*b))
                .collect()
        }
        None => f.u.iter().zip(&f.v).map(|(a, b)| a.hypot(*b)).collect(),
    };
    let max_disp =
        f.u.iter()
            .zip(&f.v)
            .map(|(a, b)| a.hypot(*b))
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
    let arrow_scale = if max_disp > 0.0 {
        2.0 * f.step_px as f64 / max_disp
    } else {
        1.0
    };
    let stride = (f.nx / 32).max(1);
    let arrows: Vec<(f64, f64, f64, f64)> = (0..f.ny)
        .step_by(stride)
        .flat_map(|j| (0..f.nx).step_by(stride).map(move |i| (i, j)))
        .filter_map(|(i, j)| {
            let q = j * f.nx + i;
            (f.u[q].is_finite())
                .then(|| (f.xs[i], f.ys[j], f.u[q] * arrow_scale, f.v[q] * arrow_scale))
        })
        .collect();
    let speed_fig = MapFigure {
        title: format!(
            "Grain speed, pair {pick} (frames {} -> {})",
            rows[pick].frame_a, rows[pick].frame_b
        ),
        label: if si.is_some() {
            "speed (m/s)".into()
        } else {
            "displacement (px)".into()
        },
        image: size,
        xs: f.xs.clone(),
        ys: f.ys.clone(),
        values: speed,
        arrows,
        outlines: outlines.clone(),
    };
    save_figure(
        &speed_fig,
        &staged.file("speed.png"),
        Some(&staged.file("speed.svg")),
    )?;
    if let Some(s) = si {
        let fig = MapFigure {
            title: format!("Max shear strain rate (eq. 2), pair {pick}"),
            label: "shear rate (1/s)".into(),
            image: size,
            xs: f.xs.clone(),
            ys: f.ys.clone(),
            values: s.shear_rate.values.clone(),
            arrows: Vec::new(),
            outlines,
        };
        save_figure(
            &fig,
            &staged.file("shear_rate.png"),
            Some(&staged.file("shear_rate.svg")),
        )?;
    }
    Ok(())
}

/// `added_mass.png/svg`: PIV's added mass (the column under the foot over the foot's velocity)
/// against foot depth beside the model's eq. 6 at `phi`, its `C` scaled with `R^2` for the
/// foot's radius `radius_m` (the paper's `C` is the 38 mm foot's; NaN: unscaled).
fn write_added_mass_figure(
    staged: &StagedDir,
    phi: f64,
    radius_m: f64,
    points: &[(f64, f64)],
) -> Result<(), FlowError> {
    let reference = sandjumper_model::params::Params::preset(phi)
        .map_err(FlowError::internal)?
        .sand
        .reference_foot_radius_m;
    let r = if radius_m.is_finite() && radius_m > 0.0 {
        radius_m
    } else {
        reference
    };
    let zmax = points.iter().map(|p| p.0).fold(0.0, f64::max) * 1.1;
    let model: Vec<(f64, f64)> = (0..=100)
        .map(|i| {
            let z = zmax * f64::from(i) / 100.0;
            let m = model_added_mass(phi, r, z).unwrap_or(f64::NAN);
            (1e3 * z, m)
        })
        .collect();
    let fig = LineFigure {
        title: "Added mass against foot depth (PIV) and the model's eq. 6".into(),
        panels: vec![LinePanel {
            caption: format!("phi = {phi}"),
            x_desc: "foot depth (mm)".into(),
            y_desc: "added mass (kg)".into(),
            lines: vec![
                Line {
                    label: "PIV: P / v_foot".into(),
                    points: points.iter().map(|p| (1e3 * p.0, p.1)).collect(),
                    color: palette(0),
                    dashed: false,
                    markers: true,
                },
                Line {
                    label: "eq. 6, preset at this phi".into(),
                    points: model,
                    color: palette(1),
                    dashed: true,
                    markers: false,
                },
            ],
            y_from_zero: true,
        }],
        size: grid_size(1),
    };
    save_figure(
        &fig,
        &staged.file("added_mass.png"),
        Some(&staged.file("added_mass.svg")),
    )?;
    Ok(())
}
