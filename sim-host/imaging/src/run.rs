//! `sandjumper track` as one call: a [`TrackRequest`] (the frames, the scale, the clock and the
//! tracking options, with the command line's defaults), [`run`] (the ball followed through the
//! frames and the jump height measured the paper's way) and a [`TrackOutcome`] that holds
//! every frame's fix in memory, serialises to `summary.json`, prints as the command's summary
//! ([`std::fmt::Display`]) and writes the output folder ([`TrackOutcome::write`]).

use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::ball::FixStatus;
use crate::error::ImagingError;
use crate::figure::{figure, thumbnail};
use crate::frame::Roi;
use crate::sequence::ImageSequence;
use crate::track::{
    Apex, CSV_HEADER, FlagCounts, FrameClock, TrackResult, TrackSpec, log_clock, track_sequence,
};
use sandjumper_acqlog::{AcqLog, Column, ReadOptions};
use sandjumper_output::parse::parse_positive_as;
use sandjumper_output::plot::save_figure;
use sandjumper_output::{Progress, StagedDir};

/// What to track and how: `sandjumper track`'s arguments, typed.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackRequest {
    /// The frames: a directory, a glob or a multi-page TIFF.
    pub frames: String,
    /// Scale, m/px (required: the default NaN is refused).
    pub m_per_px: f64,
    /// Frame rate, frames/s (frame times from the numbers in the file names).
    pub fps: Option<f64>,
    /// The acquisition log whose `camera_frame` rows time the frames (wins over `fps`);
    /// written again with `rod_height_m` into the output folder.
    pub log: Option<PathBuf>,
    /// Region of interest, px: only the ball inside counts.
    pub roi: Option<Roi>,
    /// Ball diameter, m (default 0.0095).
    pub ball_diameter_m: f64,
    /// Rest frames when the log does not say when the trajectory started (default 10).
    pub rest_frames: usize,
    /// Exposure time, s: each frame's time is its trigger plus half of it (default 0).
    pub exposure_s: f64,
    /// Half-width of the apex parabola's window, s (default 0.02).
    pub apex_window_s: f64,
}

impl Default for TrackRequest {
    fn default() -> Self {
        Self {
            frames: String::new(),
            m_per_px: f64::NAN,
            fps: None,
            log: None,
            roi: None,
            ball_diameter_m: 0.0095,
            rest_frames: 10,
            exposure_s: 0.0,
            apex_window_s: 0.02,
        }
    }
}

impl TrackRequest {
    /// A clock is needed: `fps` or `log`. (The tracking options are checked by [`run`].)
    pub fn validate(&self) -> Result<(), ImagingError> {
        if self.fps.is_none() && self.log.is_none() {
            return Err(ImagingError::input(
                "give --fps or --log to time the frames",
            ));
        }
        Ok(())
    }

    /// The tracking options.
    fn spec(&self) -> TrackSpec {
        TrackSpec {
            m_per_px: self.m_per_px,
            ball_diameter_m: self.ball_diameter_m,
            roi: self.roi,
            rest_frames: self.rest_frames,
            apex_window_s: self.apex_window_s,
            exposure_s: self.exposure_s,
        }
    }
}

/// clap value parser of [`TrackRequest::m_per_px`]: a scale, m/px, > 0.
pub fn parse_m_per_px(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a scale in metres per pixel")
}

/// clap value parser of [`TrackRequest::fps`]: a frame rate, frames/s, > 0.
pub fn parse_fps(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a frame rate in frames/s")
}

/// clap value parser of [`TrackRequest::ball_diameter_m`]: a length, m, > 0.
pub fn parse_length(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a length in metres")
}

/// clap value parser of [`TrackRequest::apex_window_s`]: a time, s, > 0.
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a time in seconds")
}

/// clap value parser of [`TrackRequest::exposure_s`]: a time, s, >= 0.
pub fn parse_exposure(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not an exposure time: seconds >= 0")),
    }
}

/// clap value parser of a ball's diameter in the image, px, > 0
/// ([`crate::camera_scale::ScaleRequest::ball_px`]).
pub fn parse_px(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a diameter in pixels")
}

/// clap value parser of a region of interest: `X,Y,W,H` in whole pixels, W and H > 0.
pub fn parse_roi(s: &str) -> Result<Roi, String> {
    let parts: Vec<Result<u32, _>> = s.split(',').map(|p| p.trim().parse::<u32>()).collect();
    match parts.as_slice() {
        [Ok(x), Ok(y), Ok(w), Ok(h)] if *w > 0 && *h > 0 => Ok(Roi {
            x: *x,
            y: *y,
            width: *w,
            height: *h,
        }),
        _ => Err(format!(
            "`{s}` is not a region: X,Y,W,H in whole pixels, W and H > 0"
        )),
    }
}

/// A tracked jump: `summary.json`'s fields (serialised in this order) and, skipped by serde,
/// every frame's fix and what the output folder is written from.
#[derive(Clone, Debug, Serialize)]
pub struct TrackOutcome {
    /// Jump height: the apex parabola's vertex (or the highest frame), m.
    pub jump_height_m: f64,
    /// Its time, s.
    pub apex_time_s: f64,
    /// The apex in full.
    pub apex: Apex,
    /// Ball centre's row at rest, px.
    pub rest_height_px: f64,
    /// Frames the rest height came from.
    pub rest_frames: usize,
    /// How they were chosen.
    pub rest_rule: String,
    /// Frames read.
    pub frames: usize,
    /// Frames flagged (missing, clipped or ambiguous: never filled in).
    pub frames_flagged: usize,
    /// By reason.
    pub flagged: FlagCounts,
    /// Scale, m/px.
    pub m_per_px: f64,
    /// `fps` or `log`.
    pub time_source: &'static str,
    /// Frame size, px.
    pub frame_size: (u32, u32),
    /// The resolved options.
    pub spec: TrackSpec,
    /// Every frame: time (s), ball centre (px), rod height (m), status.
    #[serde(skip)]
    pub result: TrackResult,
    /// The frames (the figure's thumbnail is read from them again).
    #[serde(skip)]
    pub sequence: ImageSequence,
    /// The acquisition log that timed the frames, if any.
    #[serde(skip)]
    pub log: Option<AcqLog>,
    /// The request this run answered.
    #[serde(skip)]
    pub request: TrackRequest,
}

/// Track the frames `request` names. Input is checked in this order: the sequence opened,
/// the log read, a clock given, the options and every frame (by the tracker). A note says how
/// many frames were flagged.
pub fn run(request: &TrackRequest, progress: &dyn Progress) -> Result<TrackOutcome, ImagingError> {
    run_stages(request, None, progress).map(|(outcome, _)| outcome)
}

/// [`run`], and the output folder `out` written ([`TrackOutcome::write_into`]): the folder is
/// claimed once the arguments are checked, before any frame is tracked, so a folder that
/// cannot be written is refused before the tracking. The outcome and the folder's path.
pub fn run_into(
    request: &TrackRequest,
    out: &Path,
    progress: &dyn Progress,
) -> Result<(TrackOutcome, PathBuf), ImagingError> {
    let (outcome, staged) = run_stages(request, Some(out), progress)?;
    let staged = staged.ok_or_else(|| ImagingError::Internal("no output folder".into()))?;
    let dir = outcome.write_into(staged)?;
    Ok((outcome, dir))
}

/// The stages of [`run`], the folder `out` (if any) claimed after the arguments are checked.
fn run_stages(
    request: &TrackRequest,
    out: Option<&Path>,
    progress: &dyn Progress,
) -> Result<(TrackOutcome, Option<StagedDir>), ImagingError> {
    let sequence = ImageSequence::open(&request.frames)
        .map_err(|e| ImagingError::input(format!("frames: {e}")))?;
    let log = request.log.as_deref().map(read_log).transpose()?;
    request.validate()?;
    let clock = match (&log, request.fps) {
        (Some(log), _) => log_clock(log),
        (_, fps) => FrameClock::Fps(fps.unwrap_or(f64::NAN)),
    };
    let spec = request.spec();
    let staged = out.map(StagedDir::create).transpose()?;
    let result = track_sequence(&sequence, &spec, &clock).map_err(ImagingError::input)?;
    if result.frames_flagged() > 0 {
        progress.note(&format!(
            "warning: {} of {} frames flagged (missing {}, clipped {}, ambiguous {}); see track.csv's reason column",
            result.frames_flagged(),
            result.frames.len(),
            result.flagged.missing,
            result.flagged.clipped,
            result.flagged.ambiguous
        ));
    }
    let outcome = TrackOutcome {
        jump_height_m: result.apex.jump_height_m,
        apex_time_s: result.apex.apex_time_s,
        apex: result.apex.clone(),
        rest_height_px: result.rest_height_px,
        rest_frames: result.rest_frames_used,
        rest_rule: result.rest_rule.clone(),
        frames: result.frames.len(),
        frames_flagged: result.frames_flagged(),
        flagged: result.flagged.clone(),
        m_per_px: request.m_per_px,
        time_source: if log.is_some() { "log" } else { "fps" },
        frame_size: result.frame_size,
        spec,
        result,
        sequence,
        log,
        request: request.clone(),
    };
    Ok((outcome, staged))
}

/// The acquisition log at `path`.
pub(crate) fn read_log(path: &Path) -> Result<AcqLog, ImagingError> {
    AcqLog::read_file(path, &ReadOptions::default())
        .map_err(|e| ImagingError::input(format!("--log {}: {e}", path.display())))
}

impl TrackOutcome {
    /// `summary.json` (and `track --json`): this outcome as pretty JSON.
    pub fn summary_json(&self) -> Result<String, ImagingError> {
        serde_json::to_string_pretty(self)
            .map_err(|e| ImagingError::Internal(format!("cannot encode the summary: {e}")))
    }

    /// Write `track.csv`, `summary.json`, `track.toml`, `track.png/.svg` (and, with a log,
    /// `acquisition.csv` with `rod_height_m`) into the folder `dir`, atomically; its path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, ImagingError> {
        self.write_into(StagedDir::create(dir)?)
    }

    /// Write the folder already claimed as `staged` and commit it; its path.
    pub fn write_into(&self, staged: StagedDir) -> Result<PathBuf, ImagingError> {
        let internal = |what: &str, e: &dyn fmt::Display| {
            ImagingError::Internal(format!("cannot write {what}: {e}"))
        };
        write_track_csv(&staged.file("track.csv"), &self.result)
            .map_err(|e| internal("track.csv", &e))?;
        staged.write_text("summary.json", &format!("{}\n", self.summary_json()?))?;
        self.write_settings(&staged)?;
        self.write_figure(&staged)?;
        if let Some(mut log) = self.log.clone() {
            let heights: HashMap<u64, f64> = self
                .result
                .frames
                .iter()
                .filter(|f| f.status == FixStatus::Ok)
                .map(|f| (f.frame, f.rod_height_m))
                .collect();
            log.columns = log.columns.with(Column::RodHeightM);
            for row in &mut log.rows {
                row.rod_height_m = row.camera_frame.and_then(|n| heights.get(&n).copied());
            }
            log.meta.measured_jump_height_m = Some(self.result.apex.jump_height_m);
            log.write_file(&staged.file("acquisition.csv"))
                .map_err(|e| internal("acquisition.csv", &e))?;
        }
        Ok(staged.commit()?)
    }

    /// `track.toml`: the resolved options.
    fn write_settings(&self, staged: &StagedDir) -> Result<(), ImagingError> {
        let spec_toml = toml::to_string(&self.spec)
            .map_err(|e| ImagingError::Internal(format!("cannot encode the options: {e}")))?;
        let r = &self.request;
        staged.write_text(
            "track.toml",
            &format!(
                "# The resolved options of `sandjumper track {}`{}\n{spec_toml}",
                r.frames,
                match &r.log {
                    Some(l) => format!(" --log {}", l.display()),
                    None => format!(" --fps {}", r.fps.unwrap_or_default()),
                }
            ),
        )?;
        Ok(())
    }

    /// `track.png/.svg`: the trajectory, with a thumbnail of the highest frame's ball.
    fn write_figure(&self, staged: &StagedDir) -> Result<(), ImagingError> {
        let (result, spec) = (&self.result, &self.spec);
        let top = result
            .frames
            .iter()
            .enumerate()
            .filter(|(_, f)| f.status == FixStatus::Ok)
            .max_by(|x, y| x.1.rod_height_m.total_cmp(&y.1.rod_height_m));
        let thumb = top.and_then(|(i, f)| match self.sequence.nth(i) {
            Some(Ok(sf)) => {
                let half = 1.4 * 0.5 * spec.ball_diameter_m / spec.m_per_px;
                Some(thumbnail(&sf.frame, f.frame, f.x_px, f.y_px, half))
            }
            _ => None,
        });
        let fig = figure(
            format!(
                "Rod camera: jump height {:.2} mm ({} frames, {} flagged)",
                1e3 * result.apex.jump_height_m,
                result.frames.len(),
                result.frames_flagged()
            ),
            result,
            thumb,
        );
        save_figure(
            &fig,
            &staged.file("track.png"),
            Some(&staged.file("track.svg")),
        )?;
        Ok(())
    }
}

/// The summary `sandjumper track` prints without `--json`.
impl fmt::Display for TrackOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mm = |v: f64| format!("{:.3} mm", 1e3 * v);
        let a = &self.apex;
        writeln!(
            f,
            "track: {} frames ({} flagged), time from {}",
            self.frames, self.frames_flagged, self.time_source
        )?;
        writeln!(
            f,
            "  jump height        {}  ({} at t = {:.4} s)",
            mm(a.jump_height_m),
            a.method,
            a.apex_time_s
        )?;
        writeln!(
            f,
            "  highest frame      {}  (t = {:.4} s)",
            mm(a.highest_frame_height_m),
            a.highest_frame_time_s
        )?;
        if let (Some(acc), Some(rms)) = (a.fitted_accel_m_s2, a.fit_residual_rms_m) {
            writeln!(
                f,
                "  apex fit           {} frames, acceleration {acc:.2} m/s^2, residual RMS {:.1} um",
                a.fit_frames,
                1e6 * rms
            )?;
        }
        writeln!(
            f,
            "  rest               row {:.3} px (median of {} frames: {})",
            self.rest_height_px, self.rest_frames, self.rest_rule
        )?;
        writeln!(f, "  scale              {} m/px", self.m_per_px)
    }
}

/// `track.csv`: one row per frame; a flagged frame has empty position and height and its
/// reason.
pub fn write_track_csv(path: &Path, result: &TrackResult) -> Result<(), csv::Error> {
    let mut w = csv::Writer::from_path(path)?;
    w.write_record(CSV_HEADER)?;
    let num = |v: f64| {
        if v.is_finite() {
            v.to_string()
        } else {
            String::new()
        }
    };
    for f in &result.frames {
        w.write_record([
            f.frame.to_string(),
            f.t_s.to_string(),
            num(f.x_px),
            num(f.y_px),
            num(f.rod_height_m),
            f.status.as_str().to_string(),
            f.reason.clone(),
        ])?;
    }
    w.flush()?;
    Ok(())
}
