//! `sandjumper piv` as one call: a [`PivRequest`] (the frames and every setting, with the
//! command line's defaults), [`run`] (the frames opened, timed, decoded and analysed pair by
//! pair) and a [`PivOutcome`] that holds the fields in memory, serialises to `summary.json`,
//! prints as the command's summary ([`std::fmt::Display`]) and writes the output folder
//! ([`PivOutcome::write`], in `crate::outputs`).
//!
//! ```no_run
//! use sandjumper_flow::run::{PivRequest, run};
//! let request = PivRequest { frames: "frames/".into(), fps: Some(500.0), ..PivRequest::default() };
//! let outcome = run(&request, &sandjumper_output::Silent).unwrap();
//! println!("{} pairs, first u = {} px", outcome.pairs, outcome.run.results[0].field.u[0]);
//! ```

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::analysis::{self, FlowRow, Frames, Pairing, PivOptions, PivRun};
use crate::error::FlowError;
use crate::momentum::{Calibration, Polygon};
use crate::piv::{Image, PivConfig};
use crate::preprocess::Preprocess;
use sandjumper_acqlog::{AcqLog, ReadOptions};
use sandjumper_imaging::sequence::{ImageSequence, decode_file};
use sandjumper_imaging::track::{FrameClock, frame_times, log_clock};
use sandjumper_output::parse::parse_number;
use sandjumper_output::{Progress, StagedDir};

/// What a PIV run analyses and how: `sandjumper piv`'s arguments, typed.
#[derive(Clone, Debug, PartialEq)]
pub struct PivRequest {
    /// The frames: a directory, a glob or a multi-page TIFF (as `ImageSequence::open` reads).
    pub frames: String,
    /// How frames are paired (default: consecutive).
    pub pairs: Pairing,
    /// Analyse every Nth pair, >= 1 (default 1).
    pub every: usize,
    /// The correlation passes: window sizes (px), overlap, deformation, sub-pixel estimator,
    /// validation thresholds (default: 64,32,16 px, 0.5, deformed, Gaussian, 2, 1.2).
    pub piv: PivConfig,
    /// Pre-processing of every frame (default: local contrast over 4 px, nothing else).
    pub preprocess: Preprocess,
    /// Static mask image of the frames' size: non-zero pixels are not grain flow.
    pub mask: Option<PathBuf>,
    /// The foot's outline per frame: CSV `frame,x_px,y_px`, the polygon's vertices in order.
    pub foot: Option<PathBuf>,
    /// Scale, m/px (enables the SI fields, momentum and added mass; needs `origin_px` and a
    /// clock: `fps` or `log`).
    pub m_per_px: Option<f64>,
    /// Frame rate, frames/s (ignored when `log` is given).
    pub fps: Option<f64>,
    /// Acquisition log timing the frames by its camera ticks.
    pub log: Option<PathBuf>,
    /// The foot's axis at the undisturbed surface, px (x right, y down): origin of x and height.
    pub origin_px: Option<(f64, f64)>,
    /// Packing fraction of the bed (momentum: rho phi; the eq. 6 curve), default 0.57.
    pub phi: f64,
    /// Grain density, kg/m^3 (default 1000).
    pub grain_density_kg_m3: f64,
    /// The added mass is kept only while the foot intrudes at least this fraction of its
    /// fastest intrusion, 0 to 1 (default: the paper's 0.3).
    pub min_speed_ratio: f64,
}

impl Default for PivRequest {
    fn default() -> Self {
        Self {
            frames: String::new(),
            pairs: Pairing::Consecutive,
            every: 1,
            piv: PivConfig::default(),
            preprocess: Preprocess::default(),
            mask: None,
            foot: None,
            m_per_px: None,
            fps: None,
            log: None,
            origin_px: None,
            phi: 0.57,
            grain_density_kg_m3: 1000.0,
            min_speed_ratio: analysis::DEFAULT_MIN_SPEED_RATIO,
        }
    }
}

impl PivRequest {
    /// Check what can be checked without reading a file: a scale needs the foot's axis and a
    /// clock. ([`run`] checks the passes against the frames' size once it has read them.)
    pub fn validate(&self) -> Result<(), FlowError> {
        if self.every == 0 {
            return Err(FlowError::input(
                "--every 0 not allowed (allowed: 1 or more)",
            ));
        }
        if self.m_per_px.is_some() {
            if self.origin_px.is_none() {
                return Err(FlowError::input(
                    "--m-per-px needs --origin X,Y (the foot's axis at the surface, px)",
                ));
            }
            if self.fps.is_none() && self.log.is_none() {
                return Err(FlowError::input(
                    "--m-per-px needs --fps or --log to turn displacements into velocities",
                ));
            }
        }
        Ok(())
    }

    /// Pixels to metres and the foot's axis, when both are given.
    fn calibration(&self) -> Option<Calibration> {
        match (self.m_per_px, self.origin_px) {
            (Some(m), Some(o)) => Some(Calibration {
                m_per_px: m,
                origin_px: o,
            }),
            _ => None,
        }
    }

    /// The analysis options (the static mask is read once the frames' size is known).
    fn options(&self, feet: Option<BTreeMap<u64, Polygon>>) -> PivOptions {
        PivOptions {
            piv: self.piv.clone(),
            preprocess: self.preprocess.clone(),
            pairing: self.pairs,
            every: self.every,
            calibration: self.calibration(),
            rho_phi_kg_m3: self.grain_density_kg_m3 * self.phi,
            static_mask: None,
            feet,
            min_speed_ratio: self.min_speed_ratio,
        }
    }
}

/// `--windows`: the passes' window sizes, px, comma-separated (`64,32,16`); the message
/// names the option.
pub fn parse_windows(s: &str) -> Result<Vec<usize>, FlowError> {
    s.split(',')
        .map(|p| p.trim().parse::<usize>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| {
            FlowError::input(format!(
                "--windows `{s}` is not a list of window sizes such as 64,32,16"
            ))
        })
}

/// clap value parser of `--origin`: a point `X,Y`, px.
pub fn parse_point(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<Result<f64, _>> = s.split(',').map(|p| parse_number(p.trim())).collect();
    match v.as_slice() {
        [Ok(x), Ok(y)] => Ok((*x, *y)),
        _ => Err(format!("`{s}` is not a point X,Y in pixels")),
    }
}

/// clap value parser of [`PivRequest::min_speed_ratio`]: 0 to 1.
pub fn parse_ratio(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("speed ratio {v} out of range (allowed: 0 to 1)"))
    }
}

/// clap value parser of a Gaussian's width, px: 0 (off) to 512.
pub fn parse_sigma(s: &str) -> Result<f64, String> {
    match parse_number(s) {
        Ok(v) if (0.0..=512.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "`{s}` is not a width in px (allowed: 0, off, or up to 512)"
        )),
    }
}

/// A PIV run's result: `summary.json`'s fields (serialised in this order) and, skipped by
/// serde, everything the output folder is written from, in memory.
#[derive(Clone, Debug, Serialize)]
pub struct PivOutcome {
    /// Pairs analysed.
    pub pairs: usize,
    /// Vector grid: columns, rows and spacing, px.
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
    /// Per pair: momentum (kg m/s), foot depth (m) and velocity (m/s), added mass (kg).
    pub flow: Vec<FlowRow>,
    /// The correlation passes used.
    pub piv: PivConfig,
    /// The pre-processing used.
    pub preprocess: Preprocess,
    /// The fields of every pair: displacements (px), flags, peak ratios and the SI fields.
    #[serde(skip)]
    pub run: PivRun,
    /// The frames as read (what the animation is drawn on).
    #[serde(skip)]
    pub frames: Frames,
    /// The resolved analysis options (mask and foot outlines read).
    #[serde(skip)]
    pub options: PivOptions,
    /// The request this run answered.
    #[serde(skip)]
    pub request: PivRequest,
}

impl PivOutcome {
    /// `summary.json` (and `piv --json`): this outcome as pretty JSON.
    pub fn summary_json(&self) -> Result<String, FlowError> {
        serde_json::to_string_pretty(self)
            .map_err(|e| FlowError::internal(format!("cannot encode the summary: {e}")))
    }
}

/// The summary `sandjumper piv` prints without `--json`.
impl fmt::Display for PivOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "piv: {} pairs, grid {}x{} every {} px, {} vectors ({} replaced, {} masked), median peak ratio {:.2}",
            self.pairs,
            self.grid.0,
            self.grid.1,
            self.grid.2,
            self.vectors,
            self.vectors_replaced,
            self.vectors_masked,
            self.median_peak_ratio
        )?;
        if let Some(r) = self.flow.iter().rfind(|r| r.added_mass_kg.is_finite()) {
            writeln!(
                f,
                "  last pair with the foot: depth {:.2} mm, foot velocity {:.3} m/s, momentum {:.4} kg m/s, added mass {:.4} kg",
                1e3 * r.foot_depth_m,
                r.foot_velocity_m_s,
                r.momentum_kg_m_s,
                r.added_mass_kg
            )?;
        }
        Ok(())
    }
}

/// Run the PIV analysis `request` asks for. The stages, and the order input is checked in:
/// the sequence opened (at least two frames), the frames' times (`fps` or `log`), the request
/// validated, the foot outlines read, the frames decoded, the passes checked against their
/// size, the mask read, then every pair analysed (one `advance` per pair of the stage
/// "PIV pairs"). A note says how many outliers were replaced.
pub fn run(request: &PivRequest, progress: &dyn Progress) -> Result<PivOutcome, FlowError> {
    run_stages(request, None, progress).map(|(outcome, _)| outcome)
}

/// [`run`], and the output folder `out` written ([`PivOutcome::write_into`]): the folder is
/// claimed once the arguments are checked, before any frame is decoded, so a folder that
/// cannot be written is refused before the analysis. The outcome and the folder's path.
pub fn run_into(
    request: &PivRequest,
    out: &Path,
    progress: &dyn Progress,
) -> Result<(PivOutcome, PathBuf), FlowError> {
    let (outcome, staged) = run_stages(request, Some(out), progress)?;
    let staged = staged.ok_or_else(|| FlowError::Internal("no output folder".into()))?;
    let dir = outcome.write_into(staged)?;
    Ok((outcome, dir))
}

/// The stages of [`run`], the folder `out` (if any) claimed after the arguments are checked.
fn run_stages(
    request: &PivRequest,
    out: Option<&Path>,
    progress: &dyn Progress,
) -> Result<(PivOutcome, Option<StagedDir>), FlowError> {
    let seq = open_frames(&request.frames)?;
    let numbers = seq.numbers();
    let times_s = frame_clock(request, &numbers)?;
    request.validate()?;
    let feet = request.foot.as_deref().map(read_foot).transpose()?;
    let mut opts = request.options(feet);
    let staged = out.map(StagedDir::create).transpose()?;
    let frames = decode_frames(&seq, numbers, times_s)?;
    analysis::check(&frames, &opts).map_err(FlowError::input)?;
    opts.static_mask = match &request.mask {
        Some(p) => Some(read_mask(p, frames.size())?),
        None => None,
    };
    let pairs = analysis::frame_pairs(frames.images.len(), opts.pairing, opts.every);
    progress.start("PIV pairs", Some(pairs.len() as u64));
    let run = analysis::run(&frames, &opts, || {
        progress.advance(1);
        !progress.cancelled()
    });
    progress.finish();
    let run = run.map_err(|e| {
        if progress.cancelled() {
            FlowError::Internal(e)
        } else {
            FlowError::input(e)
        }
    })?;
    let totals = run.totals();
    if totals.replaced > 0 {
        progress.note(&format!(
            "note: {} of {} vectors were outliers, replaced by their neighbours' mean (flag 1 in fields/)",
            totals.replaced,
            totals.valid + totals.replaced
        ));
    }
    let f0 = &run.results[0].field;
    let outcome = PivOutcome {
        pairs: run.results.len(),
        grid: (f0.nx, f0.ny, f0.step_px),
        vectors: totals.valid + totals.replaced + totals.masked,
        vectors_replaced: totals.replaced,
        vectors_masked: totals.masked,
        median_peak_ratio: totals.median_peak_ratio,
        calibrated: opts.calibration.is_some(),
        flow: run.rows(),
        piv: opts.piv.clone(),
        preprocess: opts.preprocess.clone(),
        run,
        frames,
        options: opts,
        request: request.clone(),
    };
    Ok((outcome, staged))
}

/// The sequence `spec` names (at least two frames), not decoded yet.
fn open_frames(spec: &str) -> Result<ImageSequence, FlowError> {
    let seq = ImageSequence::open(spec).map_err(|e| FlowError::input(format!("frames: {e}")))?;
    if seq.len() < 2 {
        return Err(FlowError::input(format!(
            "frames: {spec} holds {} frame (allowed: at least two)",
            seq.len()
        )));
    }
    Ok(seq)
}

/// The times of the frames `numbers`, s, from the log or the frame rate (`None`: not timed).
fn frame_clock(request: &PivRequest, numbers: &[u64]) -> Result<Option<Vec<f64>>, FlowError> {
    let clock = match (&request.log, request.fps) {
        (Some(p), _) => Some(log_clock(
            &AcqLog::read_file(p, &ReadOptions::default())
                .map_err(|e| FlowError::input(format!("--log {}: {e}", p.display())))?,
        )),
        (None, Some(f)) => Some(FrameClock::Fps(f)),
        (None, None) => None,
    };
    match &clock {
        Some(c) => Ok(Some(frame_times(numbers, c).map_err(FlowError::input)?)),
        None => Ok(None),
    }
}

/// Every frame of `seq`, in memory, as floats.
fn decode_frames(
    seq: &ImageSequence,
    numbers: Vec<u64>,
    times_s: Option<Vec<f64>>,
) -> Result<Frames, FlowError> {
    let mut images = Vec::with_capacity(seq.len());
    let mut max_value = 255.0f32;
    for f in seq.frames() {
        let f = f.map_err(|e| FlowError::input(format!("frames: {e}")))?;
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

/// A static mask image of the frames' size `(w, h)`: non-zero pixels are not grain flow.
fn read_mask(path: &Path, (w, h): (usize, usize)) -> Result<Vec<bool>, FlowError> {
    let m = decode_file(path).map_err(|e| FlowError::input(format!("--mask {e}")))?;
    if (m.width() as usize, m.height() as usize) != (w, h) {
        return Err(FlowError::input(format!(
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

/// Read a foot file: `frame,x_px,y_px` rows, vertices in order, at least three per frame.
pub fn read_foot(path: &Path) -> Result<BTreeMap<u64, Polygon>, FlowError> {
    let named = |e: &dyn fmt::Display| FlowError::input(format!("--foot {}: {e}", path.display()));
    let mut rdr = csv::Reader::from_path(path).map_err(|e| named(&e))?;
    let headers: Vec<String> = rdr
        .headers()
        .map_err(|e| named(&e))?
        .iter()
        .map(str::to_string)
        .collect();
    if headers != ["frame", "x_px", "y_px"] {
        return Err(named(&format!(
            "header {headers:?} (allowed: frame,x_px,y_px)"
        )));
    }
    let mut out: BTreeMap<u64, Polygon> = BTreeMap::new();
    for (line, rec) in rdr.records().enumerate() {
        let rec = rec.map_err(|e| named(&e))?;
        let bad = || {
            FlowError::input(format!(
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
        return Err(named(&format!(
            "frame {f} has {} vertices (allowed: a polygon of at least 3)",
            p.len()
        )));
    }
    Ok(out)
}
