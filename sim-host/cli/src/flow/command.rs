//! `sandjumper piv FRAMES`: PIV of side-wall grain videos, the derived fields, grain momentum
//! and added mass; `sandjumper piv-synthetic`: grain images with a known motion.

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use serde::Serialize;

use super::analysis::{
    self, FLOW_HEADER, FlowRow, Frames, PairResult, Pairing, PivOptions, PivRun, SiFields, Totals,
};
use super::figure::MapFigure;
use super::momentum::{Calibration, Polygon};
use super::piv::{Image, PivConfig, SubPixel, VectorField};
use super::preprocess::Preprocess;
use super::synthetic::GrainScene;
use crate::command::args::{parse_number, parse_positive};
use sandjumper_acqlog::{AcqLog, ReadOptions};
use sandjumper_frame::GrayFrame;
use sandjumper_imaging::render::write_png;
use sandjumper_imaging::sequence::{ImageSequence, decode_file};
use sandjumper_imaging::track::log_clock;
use sandjumper_imaging::track::{FrameClock, frame_times};
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::{palette, save_figure};

/// `--pairs`: how frames are paired ([`Pairing`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PairingArg {
    /// 1-2, 2-3, 3-4, ...
    Consecutive,
    /// 1-2, 3-4, ... (double-frame cameras).
    Ab,
}

impl From<PairingArg> for Pairing {
    fn from(p: PairingArg) -> Self {
        match p {
            PairingArg::Consecutive => Pairing::Consecutive,
            PairingArg::Ab => Pairing::Ab,
        }
    }
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
    pub pairs: PairingArg,
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
    /// Local contrast normalisation: each pixel against its neighbourhood's mean and spread
    /// (a Gaussian of this width, px, about a grain; 0: off). Gives dim, untextured grains
    /// contrast with no displacement bias.
    #[arg(long, value_name = "PX", default_value = "4", value_parser = parse_sigma)]
    pub local_contrast: f64,
    /// CLAHE tile size, px (0: no CLAHE, the default). PIVlab's 64 px tiles are fixed in the
    /// frame while the grains move through them: about 0.07 px of bias on real grain images.
    #[arg(long, value_name = "PX", default_value = "0")]
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
    /// The added mass `P / v_foot` (P: the column under the foot) is kept only while the foot
    /// intrudes at least this fraction of its fastest intrusion (the paper's 0.3; near v = 0
    /// the ratio is singular), 0 to 1.
    #[arg(long, value_name = "RATIO", default_value = "0.3", value_parser = parse_ratio)]
    pub min_speed_ratio: f64,
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
/// The stages: the sequence opened (`open_frames`), the passes (`piv_config`), the frames'
/// times (`frame_clock`), the other options (`options`), the output folder claimed, the
/// frames decoded, the passes checked against their size, the mask read, the analysis itself
/// ([`analysis::run`]), the summary and the output folder (`write_outputs`). Input is checked
/// in that order, so a bad argument is reported before any frame is decoded.
pub fn analyse(a: &PivArgs) -> Result<sandjumper_output::Analysed, CliError> {
    let seq = open_frames(a)?;
    let piv = piv_config(a)?;
    let numbers = seq.numbers();
    let times_s = frame_clock(a, &numbers)?;
    let mut opts = options(a, piv, times_s.is_some())?;
    let staged = a.out.as_deref().map(StagedDir::create).transpose()?;
    let frames = decode_frames(&seq, numbers, times_s)?;
    analysis::check(&frames, &opts).map_err(input)?;
    opts.static_mask = match &a.mask {
        Some(p) => Some(read_mask(p, frames.size())?),
        None => None,
    };
    let pairs = analysis::frame_pairs(frames.images.len(), opts.pairing, opts.every);
    let progress = crate::command::progress_bar(pairs.len() as u64, "PIV pairs");
    let run = analysis::run(&frames, &opts, || progress.inc(1)).map_err(input)?;
    progress.finish_and_clear();
    let totals = run.totals();
    let rows = run.rows();
    let report = PivReport::new(&run, &rows, &totals, &opts);
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary: {e}")))?;
    if let Some(staged) = staged {
        write_outputs(&staged, a, &frames, &opts, &run, &rows, &json)?;
        let dir = staged.commit()?;
        eprintln!("wrote {}", dir.display());
    }
    if totals.replaced > 0 {
        eprintln!(
            "note: {} of {} vectors were outliers, replaced by their neighbours' mean (flag 1 in fields/)",
            totals.replaced,
            totals.valid + totals.replaced
        );
    }
    Ok(sandjumper_output::Analysed {
        json,
        human: human_summary(&report, &rows),
    })
}

/// The sequence `a` names (at least two frames), not decoded yet.
fn open_frames(a: &PivArgs) -> Result<ImageSequence, CliError> {
    let seq = ImageSequence::open(&a.frames).map_err(|e| input(format!("frames: {e}")))?;
    if seq.len() < 2 {
        return Err(input(format!(
            "frames: {} holds {} frame (allowed: at least two)",
            a.frames,
            seq.len()
        )));
    }
    Ok(seq)
}

/// The times of the frames `numbers`, s, from `--fps` or `--log` (`None`: not timed).
fn frame_clock(a: &PivArgs, numbers: &[u64]) -> Result<Option<Vec<f64>>, CliError> {
    let clock = match (&a.log, a.fps) {
        (Some(p), _) => Some(log_clock(
            &AcqLog::read_file(p, &ReadOptions::default())
                .map_err(|e| input(format!("--log {}: {e}", p.display())))?,
        )),
        (None, Some(f)) => Some(FrameClock::Fps(f)),
        (None, None) => None,
    };
    match &clock {
        Some(c) => Ok(Some(frame_times(numbers, c).map_err(input)?)),
        None => Ok(None),
    }
}

/// Every frame of `seq`, in memory, as floats.
fn decode_frames(
    seq: &ImageSequence,
    numbers: Vec<u64>,
    times_s: Option<Vec<f64>>,
) -> Result<Frames, CliError> {
    let mut images = Vec::with_capacity(seq.len());
    let mut max_value = 255.0f32;
    for f in seq.frames() {
        let f = f.map_err(|e| input(format!("frames: {e}")))?;
        max_value = f.frame.depth().max_value();
        images.push(Image::from_frame(&f.frame));
    }
    Ok(Frames {
        numbers,
        images,
        max_value,
        times_s,
    })
}

/// The correlation passes `a` asks for.
fn piv_config(a: &PivArgs) -> Result<PivConfig, CliError> {
    Ok(PivConfig {
        windows: parse_windows(&a.windows).map_err(|e| input(format!("--windows {e}")))?,
        overlap: a.overlap,
        deform: !a.no_deform,
        subpixel: match a.subpixel {
            SubPixelArg::Gaussian => SubPixel::Gaussian,
            SubPixelArg::Parabolic => SubPixel::Parabolic,
        },
        median_threshold: a.median_threshold,
        min_peak_ratio: a.min_peak_ratio,
    })
}

/// The analysis options from the arguments and the passes `piv` (the static mask is read once
/// the frames' size is known): pre-processing, calibration (which needs frame times), the
/// foot's outlines.
fn options(a: &PivArgs, piv: PivConfig, timed: bool) -> Result<PivOptions, CliError> {
    let preprocess = Preprocess {
        local_contrast_sigma_px: a.local_contrast,
        clahe_tile_px: a.clahe_tile,
        clahe_clip: a.clahe_clip,
        subtract_background: a.subtract_background,
        cap_sigma: a.cap_sigma,
    };
    let calibration = match (a.m_per_px, a.origin) {
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
    if calibration.is_some() && !timed {
        return Err(input(
            "--m-per-px needs --fps or --log to turn displacements into velocities",
        ));
    }
    let feet = a.foot.as_deref().map(read_foot).transpose()?;
    Ok(PivOptions {
        piv,
        preprocess,
        pairing: a.pairs.into(),
        every: a.every as usize,
        calibration,
        rho_phi_kg_m3: a.grain_density * a.phi,
        static_mask: None,
        feet,
        min_speed_ratio: a.min_speed_ratio,
    })
}

fn parse_ratio(s: &str) -> Result<f64, String> {
    let v = crate::command::args::parse_number(s)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("speed ratio {v} out of range (allowed: 0 to 1)"))
    }
}

/// A static mask image of the frames' size `(w, h)`: non-zero pixels are not grain flow.
fn read_mask(path: &Path, (w, h): (usize, usize)) -> Result<Vec<bool>, CliError> {
    let m = decode_file(path).map_err(|e| input(format!("--mask {e}")))?;
    if (m.width() as usize, m.height() as usize) != (w, h) {
        return Err(input(format!(
            "--mask {}: {}x{} pixels, the frames {w}x{h} (allowed: the frames' size)",
            path.display(),
            m.width(),
            m.height()
        )));
    }
    Ok(Image::from_frame(&m)
        .data
        .iter()
        .map(|&v| v > 0.0)
        .collect())
}

impl<'a> PivReport<'a> {
    /// The summary of `run` (its `rows` and `totals`) with the settings of `opts`.
    fn new(run: &PivRun, rows: &'a [FlowRow], totals: &Totals, opts: &'a PivOptions) -> Self {
        let f0 = &run.results[0].field;
        PivReport {
            pairs: run.results.len(),
            grid: (f0.nx, f0.ny, f0.step_px),
            vectors: totals.valid + totals.replaced + totals.masked,
            vectors_replaced: totals.replaced,
            vectors_masked: totals.masked,
            median_peak_ratio: totals.median_peak_ratio,
            calibrated: opts.calibration.is_some(),
            flow: rows,
            piv: &opts.piv,
            preprocess: &opts.preprocess,
        }
    }
}

/// The text `piv` prints without `--json`.
fn human_summary(report: &PivReport<'_>, rows: &[FlowRow]) -> String {
    let mut human = format!(
        "piv: {} pairs, grid {}x{} every {} px, {} vectors ({} replaced, {} masked), median peak ratio {:.2}\n",
        report.pairs,
        report.grid.0,
        report.grid.1,
        report.grid.2,
        report.vectors,
        report.vectors_replaced,
        report.vectors_masked,
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
    human
}

fn csv_num(v: f64) -> String {
    if v.is_finite() {
        v.to_string()
    } else {
        String::new()
    }
}

fn internal(e: impl std::fmt::Display) -> CliError {
    CliError::internal(e.to_string())
}

/// Everything `--out` holds: the animation, the per-pair field tables, the stacked arrays,
/// `flow.csv` and `added_mass.csv`, `piv.toml`, the figures and `summary.json`.
fn write_outputs(
    staged: &StagedDir,
    a: &PivArgs,
    frames: &Frames,
    opts: &PivOptions,
    run: &PivRun,
    rows: &[FlowRow],
    json: &str,
) -> Result<(), CliError> {
    write_animation(staged, frames, run)?;
    write_field_tables(staged, run, opts.calibration)?;
    write_arrays(staged, run)?;
    let added_mass = run.added_mass_points();
    write_tables(staged, rows, &added_mass)?;
    write_settings(staged, a, opts)?;
    write_maps(staged, frames.size(), run, rows, opts.feet.as_ref())?;
    if !added_mass.is_empty() {
        let radius_m = PivRun::foot_radius_m(opts).unwrap_or(f64::NAN);
        write_added_mass_figure(staged, a.phi, radius_m, &added_mass)?;
    }
    staged.write_text("summary.json", &format!("{json}\n"))?;
    Ok(())
}

/// `animation.gif` (the paper's Supplementary Video 2): each pair's frame A with its vectors,
/// at most 200 frames, 100 ms each.
fn write_animation(staged: &StagedDir, frames: &Frames, run: &PivRun) -> Result<(), CliError> {
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
            super::figure::animation_frame(&frames.images[ia], &r.field, stride, scale)
        })
        .collect();
    super::figure::write_gif(&staged.file("animation.gif"), gif, 100).map_err(internal)
}

/// `fields/NNNN.csv`: one table per pair, every vector with its flag and peak ratio, and in
/// SI units when calibrated.
fn write_field_tables(
    staged: &StagedDir,
    run: &PivRun,
    cal: Option<Calibration>,
) -> Result<(), CliError> {
    let dir = staged.file("fields");
    std::fs::create_dir_all(&dir).map_err(internal)?;
    for (k, PairResult { field: f, si, .. }) in run.results.iter().enumerate() {
        let mut wtr = csv::Writer::from_path(dir.join(format!("{k:04}.csv"))).map_err(internal)?;
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
        wtr.write_record(&header).map_err(internal)?;
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
                wtr.write_record(&rec).map_err(internal)?;
            }
        }
        wtr.flush().map_err(internal)?;
    }
    Ok(())
}

/// The stacked arrays for numpy, `(pairs, rows, columns)`: displacements, flags and peak
/// ratios, and the SI fields when every pair has them.
fn write_arrays(staged: &StagedDir, run: &PivRun) -> Result<(), CliError> {
    let f0 = &run.results[0].field;
    let (nx, ny, np) = (f0.nx as u64, f0.ny as u64, run.results.len() as u64);
    let write_npy = |name: &str, shape: &[u64], data: Vec<f64>| -> Result<(), CliError> {
        sandjumper_output::write_npy(&staged.file(name), shape, data).map_err(CliError::internal)
    };
    write_npy("x_px.npy", &[nx], f0.xs.clone())?;
    write_npy("y_px.npy", &[ny], f0.ys.clone())?;
    let stack = |get: &dyn Fn(&VectorField) -> Vec<f64>| -> Vec<f64> {
        run.results.iter().flat_map(|r| get(&r.field)).collect()
    };
    write_npy("u_px.npy", &[np, ny, nx], stack(&|f| f.u.clone()))?;
    write_npy("v_px.npy", &[np, ny, nx], stack(&|f| f.v.clone()))?;
    write_npy(
        "flag.npy",
        &[np, ny, nx],
        stack(&|f| f.flag.iter().map(|&x| f64::from(x)).collect()),
    )?;
    write_npy("s2n.npy", &[np, ny, nx], stack(&|f| f.peak_ratio.clone()))?;
    let si: Vec<&SiFields> = run.results.iter().filter_map(|r| r.si.as_ref()).collect();
    if si.len() == run.results.len() {
        let pick = |get: &dyn Fn(&SiFields) -> &Vec<f64>| -> Vec<f64> {
            si.iter().flat_map(|s| get(s).iter().copied()).collect()
        };
        write_npy("u_m_s.npy", &[np, ny, nx], pick(&|s| &s.u.values))?;
        write_npy("v_m_s.npy", &[np, ny, nx], pick(&|s| &s.v.values))?;
        write_npy(
            "vorticity_1_s.npy",
            &[np, ny, nx],
            pick(&|s| &s.vorticity.values),
        )?;
        write_npy(
            "shear_rate_1_s.npy",
            &[np, ny, nx],
            pick(&|s| &s.shear_rate.values),
        )?;
    }
    Ok(())
}

/// `flow.csv` (one row per pair) and `added_mass.csv` (the table `fit added-mass` reads:
/// intruding pairs, depth increasing).
fn write_tables(
    staged: &StagedDir,
    rows: &[FlowRow],
    added_mass: &[(f64, f64)],
) -> Result<(), CliError> {
    sandjumper_output::write_csv(&staged.file("flow.csv"), rows, &FLOW_HEADER)
        .map_err(CliError::internal)?;
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

fn write_settings(staged: &StagedDir, a: &PivArgs, opts: &PivOptions) -> Result<(), CliError> {
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
        grain_density_kg_m3: a.grain_density,
        calibration: opts.calibration,
        piv: &opts.piv,
        preprocess: &opts.preprocess,
    };
    let text = toml::to_string(&settings).map_err(internal)?;
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
) -> Result<(), CliError> {
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
) -> Result<(), CliError> {
    let reference = sandjumper_model::params::Params::preset(phi)
        .map_err(internal)?
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
            let m = crate::dem::outputs::model_added_mass(phi, r, z).unwrap_or(f64::NAN);
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
    /// Move this real image (PNG, TIFF, BMP; grey or colour) instead of rendering grains:
    /// frame n is it translated by n times the shift, exactly (a Fourier shift of its mirrored
    /// extension), written as 16-bit PNG. Only with `--field shift`.
    #[arg(long, value_name = "IMAGE")]
    pub image: Option<PathBuf>,
    /// The shift per frame DX,DY, px (x right, y down) for `--field shift` (default:
    /// `--magnitude` in x and half of it in y).
    #[arg(long, value_name = "DX,DY", value_parser = parse_shift, allow_hyphen_values = true)]
    pub shift: Option<(f64, f64)>,
    /// Output directory (frame_NNNNNN.png, foot.csv for the cone, synthetic.toml).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

fn parse_sigma(s: &str) -> Result<f64, String> {
    match parse_number(s) {
        Ok(v) if (0.0..=512.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "`{s}` is not a width in px (allowed: 0, off, or up to 512)"
        )),
    }
}

fn parse_shift(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<Result<f64, _>> = s.split(',').map(|p| parse_number(p.trim())).collect();
    match v.as_slice() {
        [Ok(x), Ok(y)] if x.abs() <= 1000.0 && y.abs() <= 1000.0 => Ok((*x, *y)),
        _ => Err(format!(
            "`{s}` is not a shift DX,DY in px (each within +-1000)"
        )),
    }
}

/// `--image`: the real image's frames, each translated by its multiple of `shift`.
fn write_shifted_image(
    a: &SyntheticArgs,
    path: &Path,
    shift: (f64, f64),
    staged: &StagedDir,
) -> Result<(), CliError> {
    if a.field != SyntheticField::Shift {
        return Err(CliError::input(format!(
            "--image moves a real image by a uniform shift: it needs --field shift (given: {:?})",
            a.field
        )));
    }
    let frame = decode_file(path)
        .map_err(|e| CliError::input(format!("--image {}: {e}", path.display())))?;
    // The shift wraps around the image's periodic extension: the last frame's shift must stay
    // within a quarter of the image, where the truth is still the image moved.
    let n = f64::from(a.frames - 1);
    let (w, h) = (f64::from(frame.width()), f64::from(frame.height()));
    if (shift.0 * n).abs() > 0.25 * w || (shift.1 * n).abs() > 0.25 * h {
        return Err(CliError::input(format!(
            "--shift {},{} over {} frames moves {} ({}x{} px) by ({}, {}) px (allowed: up to a quarter of its width and height)",
            shift.0,
            shift.1,
            a.frames,
            path.display(),
            frame.width(),
            frame.height(),
            shift.0 * n,
            shift.1 * n
        )));
    }
    let scale = 65535.0 / f64::from(frame.depth().max_value());
    let img = Image::from_frame(&frame);
    for n in 0..a.frames {
        let t = f64::from(n);
        let moved = sandjumper_flow::shift::translate(&img, shift.0 * t, shift.1 * t);
        let px: Vec<u16> = moved
            .data
            .iter()
            .map(|&v| (f64::from(v) * scale).round().clamp(0.0, 65535.0) as u16)
            .collect();
        let out = GrayFrame::from_u16(frame.width(), frame.height(), px)
            .ok_or_else(|| CliError::internal("shifted frame size"))?;
        write_png(&out, &staged.file(&format!("frame_{n:06}.png"))).map_err(CliError::internal)?;
    }
    staged.write_text(
        "synthetic.toml",
        &format!(
            "# sandjumper piv-synthetic: {} moved by ({}, {}) px per frame (Fourier shift)\nimage = {:?}\nshift_px = [{}, {}]\nframes = {}\n",
            path.display(),
            shift.0,
            shift.1,
            path.display().to_string(),
            shift.0,
            shift.1,
            a.frames
        ),
    )?;
    Ok(())
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
    let shift = a.shift.unwrap_or((a.magnitude, 0.5 * a.magnitude));
    if let Some(path) = &a.image {
        write_shifted_image(a, path, shift, &staged)?;
        let dir = staged.commit()?;
        eprintln!("wrote {}", dir.display());
        return Ok(());
    }
    if a.shift.is_some() && a.field != SyntheticField::Shift {
        return Err(CliError::input(
            "--shift DX,DY is the motion of --field shift only",
        ));
    }
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
                |_, _| (shift.0 * t, shift.1 * t),
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
