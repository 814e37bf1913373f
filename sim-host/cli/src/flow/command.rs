//! `sandjumper piv FRAMES`: PIV of side-wall grain videos, the derived fields, grain momentum
//! and added mass; `sandjumper piv-synthetic`: grain images with a known motion.

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use serde::Serialize;

use super::fields::{Grid, derive};
use super::figure::MapFigure;
use super::momentum::{Calibration, Momentum, Polygon, foot_depth_m, grain_momentum, inside};
use super::piv::{Image, PivConfig, SubPixel, VectorField, flag, piv_pair};
use super::preprocess::{Preprocess, apply, background};
use super::synthetic::GrainScene;
use crate::command::args::{parse_number, parse_positive};
use sandjumper_acqlog::{AcqLog, ReadOptions};
use sandjumper_imaging::render::write_png;
use sandjumper_imaging::sequence::{ImageSequence, decode_file};
use sandjumper_imaging::track::log_clock;
use sandjumper_imaging::track::{FrameClock, frame_times};
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::{palette, save_figure};

/// How frames are paired.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Pairing {
    /// 1-2, 2-3, 3-4, ...
    Consecutive,
    /// 1-2, 3-4, ... (double-frame cameras).
    Ab,
}

fn parse_windows(s: &str) -> Result<Vec<usize>, String> {
    s.split(',')
        .map(|p| p.trim().parse::<usize>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| format!("`{s}` is not a list of window sizes such as 64,32,16"))
}

fn parse_point(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<Result<f64, _>> = s.split(',').map(|p| parse_number(p.trim())).collect();
    match v.as_slice() {
        [Ok(x), Ok(y)] => Ok((*x, *y)),
        _ => Err(format!("`{s}` is not a point X,Y in pixels")),
    }
}

/// `sandjumper piv`.
#[derive(Debug, Clone, Args)]
#[allow(clippy::struct_excessive_bools)]
pub struct PivArgs {
    /// The frames (a directory, a glob or a multi-page TIFF; see `track`).
    #[arg(value_name = "FRAMES")]
    pub frames: String,
    /// Pairing of the frames.
    #[arg(long, value_enum, default_value = "consecutive")]
    pub pairs: Pairing,
    /// Analyse every Nth pair.
    #[arg(long, value_name = "N", default_value = "1", value_parser = clap::value_parser!(u32).range(1..))]
    pub every: u32,
    /// Window sizes of the passes, px.
    #[arg(long, value_name = "N,N,..", default_value = "64,32,16")]
    pub windows: String,
    /// Window overlap, 0..=0.9.
    #[arg(long, value_name = "F", default_value = "0.5", value_parser = parse_number)]
    pub overlap: f64,
    /// Do not deform the windows (offset them by the rounded prediction instead).
    #[arg(long)]
    pub no_deform: bool,
    /// Sub-pixel peak estimator.
    #[arg(long, value_enum, default_value = "gaussian")]
    pub subpixel: SubPixelArg,
    /// Normalised median test threshold.
    #[arg(long, value_name = "X", default_value = "2", value_parser = parse_positive)]
    pub median_threshold: f64,
    /// Smallest accepted ratio of the first to the second correlation peak.
    #[arg(long, value_name = "X", default_value = "1.2", value_parser = parse_number)]
    pub min_peak_ratio: f64,
    /// CLAHE tile size, px (0: no CLAHE).
    #[arg(long, value_name = "PX", default_value = "64")]
    pub clahe_tile: usize,
    /// CLAHE clip limit (share of a tile's pixels one grey level may hold).
    #[arg(long, value_name = "F", default_value = "0.01", value_parser = parse_positive)]
    pub clahe_clip: f64,
    /// Subtract the sequence's per-pixel minimum (the static background).
    #[arg(long)]
    pub subtract_background: bool,
    /// Cap intensities at median + S standard deviations (0: off).
    #[arg(long, value_name = "S", default_value = "0", value_parser = parse_number)]
    pub cap_sigma: f64,
    /// Static mask image (same size as the frames; non-zero pixels are not grain flow).
    #[arg(long, value_name = "MASK.png")]
    pub mask: Option<PathBuf>,
    /// The foot's outline per frame: CSV `frame,x_px,y_px`, the polygon's vertices in order;
    /// inside is masked, and its lowest point gives the foot's depth and velocity.
    #[arg(long, value_name = "FOOT.csv")]
    pub foot: Option<PathBuf>,
    /// Scale, metres per pixel (enables the SI fields, momentum and added mass).
    #[arg(long, value_name = "M", value_parser = parse_positive)]
    pub m_per_px: Option<f64>,
    /// Frame rate, frames/s.
    #[arg(long, value_name = "FPS", value_parser = parse_positive, conflicts_with = "log")]
    pub fps: Option<f64>,
    /// Acquisition log timing the frames by its camera ticks.
    #[arg(long, value_name = "ACQ.csv")]
    pub log: Option<PathBuf>,
    /// The foot's axis at the undisturbed surface, px: origin of x and height.
    #[arg(long, value_name = "X,Y", value_parser = parse_point)]
    pub origin: Option<(f64, f64)>,
    /// Packing fraction of the bed (momentum: rho phi).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = crate::command::args::parse_phi)]
    pub phi: f64,
    /// Grain density, kg/m^3.
    #[arg(long, value_name = "KG_M3", default_value = "1000", value_parser = parse_positive)]
    pub grain_density: f64,
    /// Write fields/, the .npy arrays, flow.csv, added_mass.csv, figures and piv.toml into DIR.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// `--subpixel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SubPixelArg {
    /// 3-point Gaussian.
    Gaussian,
    /// 3-point parabola.
    Parabolic,
}

/// One row of `flow.csv`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlowRow {
    /// Pair index.
    pub pair: usize,
    /// Frame numbers.
    pub frame_a: u64,
    /// Frame numbers.
    pub frame_b: u64,
    /// Mid time of the pair, s (NaN without a clock).
    pub t_s: f64,
    /// Foot depth below the surface (mean over the pair), m.
    pub foot_depth_m: f64,
    /// Foot velocity, m/s (height up: negative when intruding).
    pub foot_velocity_m_s: f64,
    /// Grain momentum from the left half-plane, kg m/s.
    pub momentum_left_kg_m_s: f64,
    /// From the right.
    pub momentum_right_kg_m_s: f64,
    /// Mean, kg m/s.
    pub momentum_kg_m_s: f64,
    /// `P / v_foot`, kg.
    pub added_mass_kg: f64,
    /// Vectors measured and accepted.
    pub vectors_valid: usize,
    /// Outliers replaced.
    pub vectors_replaced: usize,
    /// Masked.
    pub vectors_masked: usize,
}

/// Header of `flow.csv`.
pub const FLOW_HEADER: [&str; 13] = [
    "pair",
    "frame_a",
    "frame_b",
    "t_s",
    "foot_depth_m",
    "foot_velocity_m_s",
    "momentum_left_kg_m_s",
    "momentum_right_kg_m_s",
    "momentum_kg_m_s",
    "added_mass_kg",
    "vectors_valid",
    "vectors_replaced",
    "vectors_masked",
];

/// `summary.json` of `piv`.
#[derive(Debug, Serialize)]
pub struct PivReport<'a> {
    /// Pairs analysed.
    pub pairs: usize,
    /// Vector grid (columns, rows) and spacing, px.
    pub grid: (usize, usize, usize),
    /// Vectors over all pairs.
    pub vectors: usize,
    /// Outliers replaced (flag 1), over all pairs.
    pub vectors_replaced: usize,
    /// Masked (flag 2), over all pairs.
    pub vectors_masked: usize,
    /// Median peak ratio of the accepted vectors.
    pub median_peak_ratio: f64,
    /// Whether SI fields were computed.
    pub calibrated: bool,
    /// Per pair.
    pub flow: &'a [FlowRow],
    /// The analysis settings.
    pub piv: &'a PivConfig,
    /// Pre-processing.
    pub preprocess: &'a Preprocess,
}

fn input(e: impl std::fmt::Display) -> CliError {
    CliError::input(e.to_string())
}

/// Read a foot file: `frame,x_px,y_px` rows, vertices in order.
pub fn read_foot(path: &Path) -> Result<std::collections::BTreeMap<u64, Polygon>, CliError> {
    let mut rdr = csv::Reader::from_path(path)
        .map_err(|e| input(format!("--foot {}: {e}", path.display())))?;
    let headers = rdr
        .headers()
        .map_err(|e| input(format!("--foot {}: {e}", path.display())))?
        .clone();
    if headers.iter().collect::<Vec<_>>() != ["frame", "x_px", "y_px"] {
        return Err(input(format!(
            "--foot {}: header {:?} (allowed: frame,x_px,y_px)",
            path.display(),
            headers.iter().collect::<Vec<_>>()
        )));
    }
    let mut out: std::collections::BTreeMap<u64, Polygon> = Default::default();
    for (line, rec) in rdr.records().enumerate() {
        let rec = rec.map_err(|e| input(format!("--foot {}: {e}", path.display())))?;
        let bad = || {
            input(format!(
                "--foot {} line {}: `{}` (allowed: frame number, then x and y in pixels)",
                path.display(),
                line + 2,
                rec.iter().collect::<Vec<_>>().join(",")
            ))
        };
        let frame: u64 = rec[0].trim().parse().map_err(|_| bad())?;
        let x = parse_number(rec[1].trim()).map_err(|_| bad())?;
        let y = parse_number(rec[2].trim()).map_err(|_| bad())?;
        out.entry(frame).or_default().push((x, y));
    }
    if let Some((f, p)) = out.iter().find(|(_, p)| p.len() < 3) {
        return Err(input(format!(
            "--foot {}: frame {f} has {} vertices (allowed: a polygon of at least 3)",
            path.display(),
            p.len()
        )));
    }
    Ok(out)
}

/// Run `sandjumper piv`.
pub fn run(a: &PivArgs) -> Result<(), CliError> {
    crate::command::print_analysed(&analyse(a)?, a.json);
    Ok(())
}

/// Run the PIV analysis `a` asks for (writing `--out` if given) without printing its summary.
pub fn analyse(a: &PivArgs) -> Result<sandjumper_output::Analysed, CliError> {
    let seq = ImageSequence::open(&a.frames).map_err(|e| input(format!("frames: {e}")))?;
    if seq.len() < 2 {
        return Err(input(format!(
            "frames: {} holds {} frame (allowed: at least two)",
            a.frames,
            seq.len()
        )));
    }
    let cfg = PivConfig {
        windows: parse_windows(&a.windows).map_err(|e| input(format!("--windows {e}")))?,
        overlap: a.overlap,
        deform: !a.no_deform,
        subpixel: match a.subpixel {
            SubPixelArg::Gaussian => SubPixel::Gaussian,
            SubPixelArg::Parabolic => SubPixel::Parabolic,
        },
        median_threshold: a.median_threshold,
        min_peak_ratio: a.min_peak_ratio,
    };
    let pre = Preprocess {
        clahe_tile_px: a.clahe_tile,
        clahe_clip: a.clahe_clip,
        subtract_background: a.subtract_background,
        cap_sigma: a.cap_sigma,
    };
    let numbers = seq.numbers();
    let clock = match (&a.log, a.fps) {
        (Some(p), _) => Some(log_clock(
            &AcqLog::read_file(p, &ReadOptions::default())
                .map_err(|e| input(format!("--log {}: {e}", p.display())))?,
        )),
        (None, Some(f)) => Some(FrameClock::Fps(f)),
        (None, None) => None,
    };
    let times = match &clock {
        Some(c) => Some(frame_times(&numbers, c).map_err(input)?),
        None => None,
    };
    let cal = match (a.m_per_px, a.origin) {
        (Some(m), Some(o)) => Some(Calibration {
            m_per_px: m,
            origin_px: o,
        }),
        (Some(_), None) => {
            return Err(input(
                "--m-per-px needs --origin X,Y (the foot's axis at the surface, px)",
            ));
        }
        _ => None,
    };
    if cal.is_some() && times.is_none() {
        return Err(input(
            "--m-per-px needs --fps or --log to turn displacements into velocities",
        ));
    }
    let foot = a.foot.as_deref().map(read_foot).transpose()?;
    let staged = a.out.as_deref().map(StagedDir::create).transpose()?;
    // Frames, in memory, as floats.
    let mut images = Vec::with_capacity(seq.len());
    let mut max_value = 255.0f32;
    for f in seq.frames() {
        let f = f.map_err(|e| input(format!("frames: {e}")))?;
        max_value = f.frame.depth().max_value();
        images.push(Image::from_frame(&f.frame));
    }
    let (w, h) = (images[0].width, images[0].height);
    super::piv::check_config(&cfg, w, h).map_err(input)?;
    let static_mask: Option<Vec<bool>> = match &a.mask {
        Some(p) => {
            let m = decode_file(p).map_err(|e| input(format!("--mask {e}")))?;
            if (m.width() as usize, m.height() as usize) != (w, h) {
                return Err(input(format!(
                    "--mask {}: {}x{} pixels, the frames {w}x{h} (allowed: the frames' size)",
                    p.display(),
                    m.width(),
                    m.height()
                )));
            }
            let img = Image::from_frame(&m);
            Some(img.data.iter().map(|&v| v > 0.0).collect())
        }
        None => None,
    };
    let bg = pre
        .subtract_background
        .then(|| background(&images.iter().collect::<Vec<_>>()))
        .flatten();
    let prepared: Vec<Image> = images
        .iter()
        .map(|i| apply(&pre, i, bg.as_ref(), max_value))
        .collect();
    let pairs: Vec<(usize, usize)> = match a.pairs {
        Pairing::Consecutive => (0..prepared.len() - 1)
            .map(|i| (i, i + 1))
            .collect::<Vec<_>>(),
        Pairing::Ab => (0..prepared.len() / 2)
            .map(|i| (2 * i, 2 * i + 1))
            .collect::<Vec<_>>(),
    }
    .into_iter()
    .step_by(a.every as usize)
    .collect();
    let progress = sandjumper_output::progress_bar(pairs.len() as u64, "PIV pairs");
    let rho_phi = a.grain_density * a.phi;
    let mut fields: Vec<VectorField> = Vec::with_capacity(pairs.len());
    let mut rows: Vec<FlowRow> = Vec::with_capacity(pairs.len());
    let mut derived: Vec<Option<(Grid, Grid, Grid, Grid)>> = Vec::new();
    for (k, &(ia, ib)) in pairs.iter().enumerate() {
        let (fa, fb) = (numbers[ia], numbers[ib]);
        let foot_a = foot.as_ref().and_then(|m| m.get(&fa));
        let foot_b = foot.as_ref().and_then(|m| m.get(&fb));
        let mask: Option<Vec<bool>> = if static_mask.is_some() || foot_a.is_some() {
            let mut m = static_mask.clone().unwrap_or_else(|| vec![false; w * h]);
            for poly in [foot_a, foot_b].into_iter().flatten() {
                // Only the polygon's bounding box can be inside it.
                let (x0, x1, y0, y1) = poly.iter().fold(
                    (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
                    |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
                );
                let span = |lo: f64, hi: f64, n: usize| {
                    (lo.floor().clamp(0.0, n as f64) as usize)
                        ..(hi.ceil() + 1.0).clamp(0.0, n as f64) as usize
                };
                for y in span(y0, y1, h) {
                    for x in span(x0, x1, w) {
                        if inside(poly, x as f64, y as f64) {
                            m[y * w + x] = true;
                        }
                    }
                }
            }
            Some(m)
        } else {
            None
        };
        let f = piv_pair(&prepared[ia], &prepared[ib], mask.as_deref(), &cfg).map_err(input)?;
        let (valid, replaced, masked) = f.counts();
        let dt = times.as_ref().map(|t| t[ib] - t[ia]);
        let t_mid = times.as_ref().map_or(f64::NAN, |t| 0.5 * (t[ia] + t[ib]));
        let mut row = FlowRow {
            pair: k,
            frame_a: fa,
            frame_b: fb,
            t_s: t_mid,
            foot_depth_m: f64::NAN,
            foot_velocity_m_s: f64::NAN,
            momentum_left_kg_m_s: f64::NAN,
            momentum_right_kg_m_s: f64::NAN,
            momentum_kg_m_s: f64::NAN,
            added_mass_kg: f64::NAN,
            vectors_valid: valid,
            vectors_replaced: replaced,
            vectors_masked: masked,
        };
        let mut d = None;
        if let (Some(cal), Some(dt)) = (cal, dt) {
            if dt <= 0.0 {
                return Err(input(format!(
                    "frames {fa} and {fb}: the second is not later than the first (dt = {dt} s)"
                )));
            }
            let m: Momentum =
                grain_momentum(&f, &cal, dt, rho_phi, mask.as_deref().map(|m| (m, w)));
            row.momentum_left_kg_m_s = m.left_kg_m_s;
            row.momentum_right_kg_m_s = m.right_kg_m_s;
            row.momentum_kg_m_s = m.momentum_kg_m_s;
            if let (Some(pa), Some(pb)) = (foot_a, foot_b) {
                let (da, db) = (foot_depth_m(pa, &cal), foot_depth_m(pb, &cal));
                row.foot_depth_m = 0.5 * (da + db);
                row.foot_velocity_m_s = -(db - da) / dt;
                if row.foot_velocity_m_s.abs() > 1e-9 {
                    row.added_mass_kg = m.momentum_kg_m_s / row.foot_velocity_m_s;
                }
            }
            let s = cal.m_per_px / dt;
            let um: Vec<f64> = f.u.iter().map(|u| u * s).collect();
            let vm: Vec<f64> = f.v.iter().map(|v| -v * s).collect();
            let spacing = f.step_px as f64 * cal.m_per_px;
            let ug = Grid::new(f.nx, f.ny, spacing, um);
            let vg = Grid::new(f.nx, f.ny, spacing, vm);
            let dd = derive(&ug, &vg);
            d = Some((ug, vg, dd.vorticity, dd.shear_rate));
        }
        derived.push(d);
        rows.push(row);
        fields.push(f);
        progress.inc(1);
    }
    progress.finish_and_clear();
    let (mut valid, mut replaced, mut masked) = (0, 0, 0);
    let mut ratios = Vec::new();
    for f in &fields {
        let c = f.counts();
        valid += c.0;
        replaced += c.1;
        masked += c.2;
        ratios.extend(
            f.peak_ratio
                .iter()
                .zip(&f.flag)
                .filter(|(_, fl)| **fl == flag::VALID)
                .map(|(r, _)| *r),
        );
    }
    ratios.sort_by(f64::total_cmp);
    let f0 = &fields[0];
    let report = PivReport {
        pairs: fields.len(),
        grid: (f0.nx, f0.ny, f0.step_px),
        vectors: valid + replaced + masked,
        vectors_replaced: replaced,
        vectors_masked: masked,
        median_peak_ratio: ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN),
        calibrated: cal.is_some(),
        flow: &rows,
        piv: &cfg,
        preprocess: &pre,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary: {e}")))?;
    if let Some(staged) = staged {
        // The animation (the paper's Supplementary Video 2): each pair's frame A with its
        // vectors, at most 200 frames, 100 ms each.
        let stride = (fields[0].nx / 40).max(1);
        let max_disp = fields
            .iter()
            .flat_map(|f| f.u.iter().zip(&f.v).map(|(a, b)| a.hypot(*b)))
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        let scale = if max_disp > 0.0 {
            1.5 * (stride * fields[0].step_px) as f64 / max_disp
        } else {
            1.0
        };
        let frames: Vec<image::RgbaImage> = pairs
            .iter()
            .zip(&fields)
            .take(200)
            .map(|(&(ia, _), f)| super::figure::animation_frame(&images[ia], f, stride, scale))
            .collect();
        super::figure::write_gif(&staged.file("animation.gif"), frames, 100)
            .map_err(CliError::internal)?;
        write_outputs(
            &staged,
            a,
            (w, h),
            &fields,
            &derived,
            &rows,
            foot.as_ref(),
            &json,
        )?;
        let dir = staged.commit()?;
        eprintln!("wrote {}", dir.display());
    }
    if replaced > 0 {
        eprintln!(
            "note: {replaced} of {} vectors were outliers, replaced by their neighbours' mean (flag 1 in fields/)",
            valid + replaced
        );
    }
    let mut human = format!(
        "piv: {} pairs, grid {}x{} every {} px, {} vectors ({} replaced, {} masked), median peak ratio {:.2}\n",
        report.pairs,
        report.grid.0,
        report.grid.1,
        report.grid.2,
        report.vectors,
        replaced,
        masked,
        report.median_peak_ratio
    );
    if let Some(r) = rows.iter().rfind(|r| r.added_mass_kg.is_finite()) {
        human += &format!(
            "  last pair with the foot: depth {:.2} mm, foot velocity {:.3} m/s, momentum {:.4} kg m/s, added mass {:.4} kg\n",
            1e3 * r.foot_depth_m,
            r.foot_velocity_m_s,
            r.momentum_kg_m_s,
            r.added_mass_kg
        );
    }
    Ok(sandjumper_output::Analysed { json, human })
}

fn csv_num(v: f64) -> String {
    if v.is_finite() {
        v.to_string()
    } else {
        String::new()
    }
}

#[allow(clippy::too_many_arguments)]
fn write_outputs(
    staged: &StagedDir,
    a: &PivArgs,
    (w, h): (usize, usize),
    fields: &[VectorField],
    derived: &[Option<(Grid, Grid, Grid, Grid)>],
    rows: &[FlowRow],
    foot: Option<&std::collections::BTreeMap<u64, Polygon>>,
    json: &str,
) -> Result<(), CliError> {
    let err = |e: &dyn std::fmt::Display| CliError::internal(e.to_string());
    let dir = staged.file("fields");
    std::fs::create_dir_all(&dir).map_err(|e| err(&e))?;
    let cal = a.m_per_px.zip(a.origin).map(|(m, o)| Calibration {
        m_per_px: m,
        origin_px: o,
    });
    for (k, (f, d)) in fields.iter().zip(derived).enumerate() {
        let mut wtr =
            csv::Writer::from_path(dir.join(format!("{k:04}.csv"))).map_err(|e| err(&e))?;
        let mut header = vec!["x_px", "y_px", "u_px", "v_px", "flag", "s2n"];
        if d.is_some() {
            header.extend([
                "x_m",
                "h_m",
                "u_m_s",
                "v_m_s",
                "vorticity_1_s",
                "shear_rate_1_s",
            ]);
        }
        wtr.write_record(&header).map_err(|e| err(&e))?;
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
                if let (Some((u, v, vo, sh)), Some(c)) = (d, cal) {
                    rec.extend([
                        c.x_m(f.xs[i]).to_string(),
                        c.h_m(f.ys[j]).to_string(),
                        csv_num(u.values[q]),
                        csv_num(v.values[q]),
                        csv_num(vo.values[q]),
                        csv_num(sh.values[q]),
                    ]);
                }
                wtr.write_record(&rec).map_err(|e| err(&e))?;
            }
        }
        wtr.flush().map_err(|e| err(&e))?;
    }
    // Stacked arrays for numpy: (pairs, rows, columns).
    let (nx, ny, np) = (
        fields[0].nx as u64,
        fields[0].ny as u64,
        fields.len() as u64,
    );
    let write_npy = |name: &str, shape: &[u64], data: Vec<f64>| -> Result<(), CliError> {
        sandjumper_output::write_npy(&staged.file(name), shape, data).map_err(CliError::internal)
    };
    write_npy("x_px.npy", &[nx], fields[0].xs.clone())?;
    write_npy("y_px.npy", &[ny], fields[0].ys.clone())?;
    let stack = |get: &dyn Fn(&VectorField) -> Vec<f64>| -> Vec<f64> {
        fields.iter().flat_map(get).collect()
    };
    write_npy("u_px.npy", &[np, ny, nx], stack(&|f| f.u.clone()))?;
    write_npy("v_px.npy", &[np, ny, nx], stack(&|f| f.v.clone()))?;
    write_npy(
        "flag.npy",
        &[np, ny, nx],
        stack(&|f| f.flag.iter().map(|&x| f64::from(x)).collect()),
    )?;
    write_npy("s2n.npy", &[np, ny, nx], stack(&|f| f.peak_ratio.clone()))?;
    if derived.iter().all(Option::is_some) {
        let pick = |k: usize| -> Vec<f64> {
            derived
                .iter()
                .flatten()
                .flat_map(|d| match k {
                    0 => d.0.values.clone(),
                    1 => d.1.values.clone(),
                    2 => d.2.values.clone(),
                    _ => d.3.values.clone(),
                })
                .collect()
        };
        write_npy("u_m_s.npy", &[np, ny, nx], pick(0))?;
        write_npy("v_m_s.npy", &[np, ny, nx], pick(1))?;
        write_npy("vorticity_1_s.npy", &[np, ny, nx], pick(2))?;
        write_npy("shear_rate_1_s.npy", &[np, ny, nx], pick(3))?;
    }
    sandjumper_output::write_csv(&staged.file("flow.csv"), rows, &FLOW_HEADER)
        .map_err(CliError::internal)?;
    // The table `fit added-mass` reads: intruding pairs, depth increasing.
    let mut am = String::from("depth_m,added_mass_kg\n");
    let mut last = f64::MIN;
    let mut am_points = Vec::new();
    for r in rows {
        if r.added_mass_kg.is_finite() && r.foot_velocity_m_s < 0.0 && r.foot_depth_m > last {
            am += &format!("{},{}\n", r.foot_depth_m, r.added_mass_kg);
            last = r.foot_depth_m;
            am_points.push((r.foot_depth_m, r.added_mass_kg));
        }
    }
    staged.write_text("added_mass.csv", &am)?;
    staged.write_text(
        "piv.toml",
        &format!(
            "# sandjumper piv {}: the resolved settings\n{}",
            a.frames,
            toml::to_string(
                &serde_json::from_str::<serde_json::Value>(json)
                    .map_err(|e| err(&e))?
                    .as_object()
                    .map(|o| {
                        let mut o = o.clone();
                        o.remove("flow");
                        o
                    })
            )
            .map_err(|e| err(&e))?
        ),
    )?;
    // Figures of the pair with the largest momentum (or the middle pair).
    let pick = rows
        .iter()
        .enumerate()
        .filter(|(_, r)| r.momentum_kg_m_s.is_finite())
        .max_by(|x, y| {
            x.1.momentum_kg_m_s
                .abs()
                .total_cmp(&y.1.momentum_kg_m_s.abs())
        })
        .map_or(fields.len() / 2, |(k, _)| k);
    let f = &fields[pick];
    let outline: Vec<Vec<(f64, f64)>> = foot
        .and_then(|m| m.get(&rows[pick].frame_a))
        .cloned()
        .into_iter()
        .collect();
    let speed: Vec<f64> = match &derived[pick] {
        Some((u, v, _, _)) => u
            .values
            .iter()
            .zip(&v.values)
            .map(|(a, b)| a.hypot(*b))
            .collect(),
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
    let calibrated = derived[pick].is_some();
    let speed_fig = MapFigure {
        title: format!(
            "Grain speed, pair {pick} (frames {} -> {})",
            rows[pick].frame_a, rows[pick].frame_b
        ),
        label: if calibrated {
            "speed (m/s)".into()
        } else {
            "displacement (px)".into()
        },
        image: (w, h),
        xs: f.xs.clone(),
        ys: f.ys.clone(),
        values: speed,
        arrows,
        outlines: outline.clone(),
    };
    save_figure(
        &speed_fig,
        &staged.file("speed.png"),
        Some(&staged.file("speed.svg")),
    )?;
    if let Some((_, _, _, shear)) = &derived[pick] {
        let fig = MapFigure {
            title: format!("Max shear strain rate (eq. 2), pair {pick}"),
            label: "shear rate (1/s)".into(),
            image: (w, h),
            xs: f.xs.clone(),
            ys: f.ys.clone(),
            values: shear.values.clone(),
            arrows: Vec::new(),
            outlines: outline,
        };
        save_figure(
            &fig,
            &staged.file("shear_rate.png"),
            Some(&staged.file("shear_rate.svg")),
        )?;
    }
    if !am_points.is_empty() {
        let params = sandjumper_model::params::Params::preset(a.phi).map_err(|e| err(&e))?;
        let sand = sandjumper_model::ground::Sand::new(
            &params,
            sandjumper_model::ground::GroundLaw::resolve(
                sandjumper_model::params::ModelName::Eq4,
                &params.model,
            ),
        );
        let zmax = am_points.iter().map(|p| p.0).fold(0.0, f64::max) * 1.1;
        let model: Vec<(f64, f64)> = (0..=100)
            .map(|i| {
                let z = zmax * f64::from(i) / 100.0;
                (1e3 * z, sand.added_mass(z))
            })
            .collect();
        let fig = LineFigure {
            title: "Added mass against foot depth (PIV) and the model's eq. 6".into(),
            panels: vec![LinePanel {
                caption: format!("phi = {}", a.phi),
                x_desc: "foot depth (mm)".into(),
                y_desc: "added mass (kg)".into(),
                lines: vec![
                    Line {
                        label: "PIV: P / v_foot".into(),
                        points: am_points.iter().map(|p| (1e3 * p.0, p.1)).collect(),
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
    }
    staged.write_text("summary.json", &format!("{json}\n"))?;
    Ok(())
}

/// A known motion of `piv-synthetic`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SyntheticField {
    /// Every grain moves by (MAG, MAG/2) px per frame.
    Shift,
    /// u = MAG * (y - H/2) / (H/2) px per frame: a shear.
    Shear,
    /// A rigid rotation about the centre, MAG px per frame at the edge.
    Rotation,
    /// A flat foot (half-width H/4) descending MAG px per frame from a surface at H/4, with
    /// the 60-degree cone of grains under it moving along and the rest at rest.
    Cone,
}

/// `sandjumper piv-synthetic`.
#[derive(Debug, Clone, Args)]
pub struct SyntheticArgs {
    /// The motion.
    #[arg(long, value_enum)]
    pub field: SyntheticField,
    /// Magnitude, px per frame.
    #[arg(long, value_name = "PX", default_value = "2.5", value_parser = parse_number)]
    pub magnitude: f64,
    /// Frame size WxH, px.
    #[arg(long, value_name = "WxH", default_value = "1280x1024", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Frames to write.
    #[arg(long, value_name = "N", default_value = "2", value_parser = clap::value_parser!(u32).range(2..=10000))]
    pub frames: u32,
    /// Grain diameter, px.
    #[arg(long, value_name = "PX", default_value = "5", value_parser = parse_positive)]
    pub grain_px: f64,
    /// Read noise, 8-bit levels RMS (0: none).
    #[arg(long, value_name = "LEVELS", default_value = "0", value_parser = parse_number)]
    pub noise: f64,
    /// Seed.
    #[arg(long, value_name = "N", default_value = "1")]
    pub seed: u64,
    /// Output directory (frame_NNNNNN.png, foot.csv for the cone, synthetic.toml).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let v: Vec<Result<u32, _>> = s.split('x').map(str::parse).collect();
    match v.as_slice() {
        [Ok(w), Ok(h)] if (16..=16384).contains(w) && (16..=16384).contains(h) => Ok((*w, *h)),
        _ => Err(format!("`{s}` is not a size WxH (16..=16384 px each)")),
    }
}

/// The displacement of the cone scene after `t` frames of `mag` px: grains in the cone move
/// with the foot.
pub fn cone_displacement(w: f64, h: f64, mag: f64, t: f64) -> impl Fn(f64, f64) -> (f64, f64) {
    let (axis, surface, half) = (0.5 * w, 0.25 * h, 0.25 * h);
    let tan = 60f64.to_radians().tan();
    move |x, y| {
        let depth = y - surface;
        let r = (x - axis).abs();
        if depth >= 0.0 && r < half - depth / tan {
            (0.0, mag * t)
        } else {
            (0.0, 0.0)
        }
    }
}

/// Run `sandjumper piv-synthetic`.
pub fn run_synthetic(a: &SyntheticArgs) -> Result<(), CliError> {
    let staged = StagedDir::create(&a.out)?;
    let scene = GrainScene {
        width: a.size.0,
        height: a.size.1,
        grain_px: a.grain_px,
        noise: a.noise.max(0.0),
        seed: a.seed,
        ..GrainScene::default()
    };
    let grains = scene.grains();
    let (w, h) = (f64::from(a.size.0), f64::from(a.size.1));
    let mag = a.magnitude;
    let surface = 0.25 * h;
    let mut foot = String::from("frame,x_px,y_px\n");
    for n in 0..a.frames {
        let t = f64::from(n);
        let frame = match a.field {
            SyntheticField::Shift => scene.render(
                &grains,
                |_, _| (mag * t, 0.5 * mag * t),
                |_, _| false,
                u64::from(n),
            ),
            SyntheticField::Shear => scene.render(
                &grains,
                |_, y| (mag * t * (y - 0.5 * h) / (0.5 * h), 0.0),
                |_, _| false,
                u64::from(n),
            ),
            SyntheticField::Rotation => {
                let om = mag / (0.5 * w.min(h));
                scene.render(
                    &grains,
                    |x, y| {
                        let (dx, dy) = (x - 0.5 * w, y - 0.5 * h);
                        let (c, s) = ((om * t).cos(), (om * t).sin());
                        (dx * c - dy * s - dx, dx * s + dy * c - dy)
                    },
                    |_, _| false,
                    u64::from(n),
                )
            }
            SyntheticField::Cone => {
                let bottom = surface + mag * t;
                let (x0, x1) = (0.5 * w - 0.25 * h, 0.5 * w + 0.25 * h);
                for (x, y) in [(x0, 0.0), (x1, 0.0), (x1, bottom), (x0, bottom)] {
                    foot += &format!("{n},{x},{y}\n");
                }
                scene.render(
                    &grains,
                    cone_displacement(w, h, mag, t),
                    move |_, y| y < surface,
                    u64::from(n),
                )
            }
        };
        write_png(&frame, &staged.file(&format!("frame_{n:06}.png")))
            .map_err(CliError::internal)?;
    }
    if a.field == SyntheticField::Cone {
        staged.write_text("foot.csv", &foot)?;
    }
    staged.write_text(
        "synthetic.toml",
        &format!(
            "# sandjumper piv-synthetic: {:?}, {} px per frame\nfield = \"{:?}\"\nmagnitude_px = {}\nframes = {}\n{}",
            a.field,
            mag,
            a.field,
            mag,
            a.frames,
            toml::to_string(&scene).map_err(|e| CliError::internal(e.to_string()))?
        ),
    )?;
    let dir = staged.commit()?;
    eprintln!("wrote {}", dir.display());
    Ok(())
}
