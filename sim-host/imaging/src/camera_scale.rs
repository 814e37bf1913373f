//! `sandjumper camera-scale` as one call: a [`ScaleRequest`] (the frames of a slow motor move
//! and its acquisition log), [`run`] (the ball followed, its row fitted against the encoder's
//! position) and a [`ScaleOutcome`]: the camera's metres per pixel, serialised as the
//! command's `--json` and printed as its one-line summary ([`std::fmt::Display`]).

use std::collections::HashMap;
use std::fmt;
use std::path::PathBuf;

use serde::Serialize;

use crate::ball::{BallFinder, FixStatus};
use crate::error::ImagingError;
use crate::frame::Roi;
use crate::run::read_log;
use crate::scale::{ScaleFit, fit_scale};
use crate::sequence::ImageSequence;
use crate::track::{follow_ball, frame_times, log_clock};
use sandjumper_acqlog::AcqLog;
use sandjumper_output::Progress;

/// What to measure the scale from: `sandjumper camera-scale`'s arguments, typed. Every field
/// is required (the command line has no defaults here but `roi`), so there is no `Default`.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ScaleRequest {
    /// The frames of the slow move (as for `track`).
    #[cfg_attr(feature = "clap", arg(value_name = "FRAMES"))]
    pub frames: String,
    /// The acquisition log of the move: its `camera_frame` rows give the encoder position of
    /// each frame.
    #[cfg_attr(feature = "clap", arg(long, value_name = "ACQ.csv"))]
    pub log: PathBuf,
    /// The ball's diameter in the image, px (roughly: it sets which bright objects count).
    #[cfg_attr(feature = "clap", arg(long, value_name = "PX", value_parser = crate::run::parse_px))]
    pub ball_px: f64,
    /// Region of interest X,Y,W,H, px.
    #[cfg_attr(feature = "clap", arg(long, value_name = "X,Y,W,H", value_parser = crate::run::parse_roi))]
    pub roi: Option<Roi>,
}

/// The scale measured: the fit (flattened into the JSON) and the frames it came from.
#[derive(Clone, Debug, Serialize)]
pub struct ScaleOutcome {
    /// The fit: m/px, slope (px/m), R^2, residual RMS (px), frames used, travel (m).
    #[serde(flatten)]
    pub fit: ScaleFit,
    /// Frames read.
    pub frames: usize,
    /// Frames flagged (not in the fit).
    pub frames_flagged: usize,
}

/// Measure the camera's scale `request` asks for. A note warns when the ball moved up as the
/// position grew (the rod clamped instead of the carriage?).
pub fn run(request: &ScaleRequest, progress: &dyn Progress) -> Result<ScaleOutcome, ImagingError> {
    let seq = ImageSequence::open(&request.frames)
        .map_err(|e| ImagingError::input(format!("frames: {e}")))?;
    let log = read_log(&request.log)?;
    let outcome = scale_from(&seq, &log, request.ball_px, request.roi)?;
    if !outcome.fit.direction_ok {
        progress.note(
            "warning: the ball moved up in the image as p grew; with the carriage clamped it moves down. Was the rod clamped instead (the scale is still |slope|)?",
        );
    }
    Ok(outcome)
}

/// Fit the scale of `seq` against `log`, following a ball of `ball_px` px inside `roi`.
pub fn scale_from(
    seq: &ImageSequence,
    log: &AcqLog,
    ball_px: f64,
    roi: Option<Roi>,
) -> Result<ScaleOutcome, ImagingError> {
    frame_times(&seq.numbers(), &log_clock(log)).map_err(ImagingError::input)?;
    let positions = log.positions_m();
    let p_of: HashMap<u64, f64> = log
        .rows
        .iter()
        .zip(&positions)
        .filter_map(|(r, p)| r.camera_frame.map(|n| (n, *p)))
        .collect();
    let finder = BallFinder {
        radius_px: 0.5 * ball_px,
    };
    let followed = follow_ball(seq, &finder, roi).map_err(ImagingError::input)?;
    let pairs: Vec<(f64, f64)> = followed
        .fixes
        .iter()
        .filter(|(_, f)| f.status == FixStatus::Ok)
        .filter_map(|(n, f)| p_of.get(n).map(|p| (*p, f.y_px)))
        .collect();
    let flagged = followed.fixes.len() - pairs.len();
    let fit = fit_scale(&pairs).map_err(|e| ImagingError::input(format!("camera-scale: {e}")))?;
    Ok(ScaleOutcome {
        fit,
        frames: followed.fixes.len(),
        frames_flagged: flagged,
    })
}

impl ScaleOutcome {
    /// `camera-scale --json`: this outcome as pretty JSON.
    pub fn summary_json(&self) -> Result<String, ImagingError> {
        serde_json::to_string_pretty(self)
            .map_err(|e| ImagingError::Internal(format!("cannot encode the result: {e}")))
    }
}

/// The line `sandjumper camera-scale` prints without `--json`.
impl fmt::Display for ScaleOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let fit = &self.fit;
        writeln!(
            f,
            "camera scale: {:.6e} m/px ({:.2} px/mm), {} frames ({} flagged), travel {:.2} mm, R^2 {:.6}, residual RMS {:.3} px",
            fit.m_per_px,
            1e-3 / fit.m_per_px,
            self.frames,
            self.frames_flagged,
            1e3 * fit.travel_m,
            fit.r_squared,
            fit.residual_rms_px
        )
    }
}
