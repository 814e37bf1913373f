//! Tracking the rod's ball through an image sequence and the jump height measured the
//! paper's way: "the maximal rod position minus the initial rod position at rest".
//!
//! - **Time** of each frame: from the frame rate (`number / fps`, numbers from the file
//!   names, counted from the first), or from the acquisition log's `camera_frame` rows (the
//!   firmware triggered each frame, so the log knows when), plus half the exposure (a moving
//!   ball's centroid is its mean position over the exposure).
//! - **Rest height**: the median ball position over the rest frames: the frames taken before
//!   the log's first `RUNNING` sample, or (no log, or no flags in it) the first
//!   `rest_frames` frames.
//! - **Jump height**: a parabola (free flight) fitted by least squares to the frames within
//!   `apex_window_s` of the highest frame; its vertex is the jump height. The highest frame is
//!   reported too: at 200 fps it lies below the true apex by up to `g (2.5 ms)^2 / 2 = 31 um`.

use sandjumper_acqlog::AcqLog;
use sandjumper_core::sample::flags;
use serde::Serialize;

use super::ball::{BallFinder, BallFix, FixStatus, solve3};
use super::frame::Roi;
use super::sequence::{ImageSequence, SequenceError};

/// How to track and measure.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrackSpec {
    /// Scale, metres per pixel.
    pub m_per_px: f64,
    /// Ball diameter, m.
    pub ball_diameter_m: f64,
    /// Region of interest (the whole frame when `None`).
    pub roi: Option<Roi>,
    /// Rest frames when the log does not say when the trajectory started.
    pub rest_frames: usize,
    /// Half-width of the apex fit's window, s.
    pub apex_window_s: f64,
    /// Exposure time, s (frame time = trigger + exposure / 2).
    pub exposure_s: f64,
}

impl TrackSpec {
    /// Defaults for a scale: the paper's 9.5 mm ball, 10 rest frames, +-20 ms apex window.
    pub fn new(m_per_px: f64) -> Self {
        Self {
            m_per_px,
            ball_diameter_m: 9.5e-3,
            roi: None,
            rest_frames: 10,
            apex_window_s: 0.02,
            exposure_s: 0.0,
        }
    }
}

/// When each frame was taken.
#[derive(Clone, Debug, PartialEq)]
pub enum FrameClock {
    /// A fixed rate, frames/s.
    Fps(f64),
    /// The trigger time of each camera frame from a log, by frame number; `running_from_s`:
    /// the first `RUNNING` sample's time, if the log has flags.
    Log {
        /// `(camera_frame, t_s)` in log order.
        frames: Vec<(u64, f64)>,
        /// Time of the first sample flagged `RUNNING`, s.
        running_from_s: Option<f64>,
    },
}

/// Why tracking could not run (bad input: exit status 2). Each message names the flag or the
/// frames and says what is allowed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TrackError {
    /// `--fps` is not a positive frame rate.
    #[error("--fps {0} not allowed (allowed: a frame rate > 0 frames/s)")]
    FrameRate(f64),
    /// The log that should time the frames has no camera frames.
    #[error(
        "the log has no camera frames (no `camera_frame` values): it cannot time the frames; use --fps"
    )]
    NoCameraFrames,
    /// The log lists one camera frame twice.
    #[error("the log lists camera frame {0} twice")]
    FrameTwice(u64),
    /// The frames and the log's camera ticks are not the same frame numbers.
    #[error("{}", log_disagreement(*.images, *.ticks, .not_in_log, .without_image))]
    LogDisagrees {
        /// How many images the sequence has.
        images: usize,
        /// How many camera ticks the log has.
        ticks: usize,
        /// Frame numbers of images that the log does not list.
        not_in_log: Vec<u64>,
        /// Frame numbers the log lists without an image.
        without_image: Vec<u64>,
    },
    /// The region of interest does not lie inside the frames.
    #[error(
        "--roi {},{},{},{} lies outside the {}x{} frames of {sequence} (allowed: inside the frame, not empty)",
        roi.x, roi.y, roi.width, roi.height, frame.0, frame.1
    )]
    RoiOutside {
        /// The region asked for, px.
        roi: Roi,
        /// The frames' width and height, px.
        frame: (u32, u32),
        /// The image sequence, as named to the user.
        sequence: String,
    },
    /// A length, scale or window that must be positive is not.
    #[error("{flag} {value} not allowed (allowed: finite and > 0)")]
    NotPositive {
        /// The flag, e.g. `--m-per-px`.
        flag: &'static str,
        /// The value given.
        value: f64,
    },
    /// A negative or non-finite exposure.
    #[error("--exposure {0} not allowed (allowed: finite and >= 0 s)")]
    Exposure(f64),
    /// No rest frame asked for.
    #[error("--rest-frames 0 not allowed (allowed: >= 1)")]
    NoRestFrames,
    /// The ball was not measured in any rest frame.
    #[error(
        "no rest frame with the ball measured ({rest_frames} rest frames: {rule}); the rest height is unknown"
    )]
    RestUnmeasured {
        /// How many frames the rule took as rest frames.
        rest_frames: usize,
        /// Which frames are the rest frames.
        rule: String,
    },
    /// The ball was not measured in any frame.
    #[error("no frame with the ball measured")]
    NeverMeasured,
    /// A frame of the sequence could not be read (its message, not a separate error source).
    #[error("frames: {0}")]
    Frames(SequenceError),
}

impl From<SequenceError> for TrackError {
    fn from(e: SequenceError) -> Self {
        Self::Frames(e)
    }
}

/// [`TrackError::LogDisagrees`]'s message: the counts, then up to five frame numbers of each kind.
fn log_disagreement(
    images: usize,
    ticks: usize,
    not_in_log: &[u64],
    without_image: &[u64],
) -> String {
    let list = |v: &[u64]| {
        let shown: Vec<String> = v.iter().take(5).map(u64::to_string).collect();
        format!(
            "{}{}",
            shown.join(", "),
            if v.len() > 5 { ", ..." } else { "" }
        )
    };
    let mut why =
        format!("the frames ({images} images) and the log ({ticks} camera ticks) disagree");
    if !not_in_log.is_empty() {
        why += &format!(
            "; {} frame number(s) not in the log: {}",
            not_in_log.len(),
            list(not_in_log)
        );
    }
    if !without_image.is_empty() {
        why += &format!(
            "; {} camera tick(s) without an image: frame {}",
            without_image.len(),
            list(without_image)
        );
    }
    why
}

/// One tracked frame (a row of `track.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrackedFrame {
    /// Frame number.
    pub frame: u64,
    /// Time, s.
    pub t_s: f64,
    /// Ball centre, px (NaN when flagged): pixel (row i, column j) is centred at x = j,
    /// y = i, as numpy, scikit-image, trackpy and OpenCV have it.
    pub x_px: f64,
    /// Ball centre, px, `y` downward (NaN when flagged); the same pixel convention.
    pub y_px: f64,
    /// Rod height above rest, m (NaN when flagged).
    pub rod_height_m: f64,
    /// `ok`, `missing`, `clipped` or `ambiguous`.
    pub status: FixStatus,
    /// Why the frame is flagged.
    pub reason: String,
}

/// Header of `track.csv`.
pub const CSV_HEADER: [&str; 7] = [
    "frame",
    "t_s",
    "x_px",
    "y_px",
    "rod_height_m",
    "status",
    "reason",
];

/// The apex: fitted and sampled.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Apex {
    /// Jump height: the fitted parabola's vertex, or the highest frame if no fit, m.
    pub jump_height_m: f64,
    /// Its time, s.
    pub apex_time_s: f64,
    /// `parabola` or `highest_frame` (too few frames around the top to fit).
    pub method: &'static str,
    /// The highest frame's rod height, m.
    pub highest_frame_height_m: f64,
    /// Its time, s.
    pub highest_frame_time_s: f64,
    /// The parabola's acceleration, m/s^2 (free flight: about -9.81).
    pub fitted_accel_m_s2: Option<f64>,
    /// Frames in the fit.
    pub fit_frames: usize,
    /// RMS of the fit's residuals, m.
    pub fit_residual_rms_m: Option<f64>,
}

/// Counts of flagged frames by reason.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FlagCounts {
    /// No ball found.
    pub missing: usize,
    /// Ball at the edge.
    pub clipped: usize,
    /// Two candidates.
    pub ambiguous: usize,
}

/// Everything a tracking run measured.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackResult {
    /// Every frame, in order.
    pub frames: Vec<TrackedFrame>,
    /// Ball centre at rest (median over the rest frames), px.
    pub rest_height_px: f64,
    /// Frames the rest height was taken from.
    pub rest_frames_used: usize,
    /// How the rest frames were chosen.
    pub rest_rule: String,
    /// The apex.
    pub apex: Apex,
    /// Flagged frames by reason.
    pub flagged: FlagCounts,
    /// Frame size, px.
    pub frame_size: (u32, u32),
}

impl TrackResult {
    /// Frames flagged (not measured).
    pub fn frames_flagged(&self) -> usize {
        self.flagged.missing + self.flagged.clipped + self.flagged.ambiguous
    }
}

/// Frames not measured for longer than this many frames: the next search covers the
/// whole region again.
const LOST_AFTER_FRAMES: u64 = 3;

/// The trigger time of each frame number of `numbers`, s; the log and the sequence must hold
/// the same frame numbers.
pub fn frame_times(numbers: &[u64], clock: &FrameClock) -> Result<Vec<f64>, TrackError> {
    match clock {
        FrameClock::Fps(fps) => {
            if !(fps.is_finite() && *fps > 0.0) {
                return Err(TrackError::FrameRate(*fps));
            }
            let first = numbers.first().copied().unwrap_or(0);
            Ok(numbers.iter().map(|&n| (n - first) as f64 / fps).collect())
        }
        FrameClock::Log { frames, .. } => {
            if frames.is_empty() {
                return Err(TrackError::NoCameraFrames);
            }
            let mut by_number: Vec<(u64, f64)> = frames.clone();
            by_number.sort_by_key(|f| f.0);
            if let Some(w) = by_number.windows(2).find(|w| w[0].0 == w[1].0) {
                return Err(TrackError::FrameTwice(w[0].0));
            }
            let in_log = |n: u64| by_number.binary_search_by_key(&n, |f| f.0).ok();
            let missing_in_log: Vec<u64> = numbers
                .iter()
                .copied()
                .filter(|&n| in_log(n).is_none())
                .collect();
            let missing_frames: Vec<u64> = by_number
                .iter()
                .map(|f| f.0)
                .filter(|n| numbers.binary_search(n).is_err())
                .collect();
            if !missing_in_log.is_empty() || !missing_frames.is_empty() {
                return Err(TrackError::LogDisagrees {
                    images: numbers.len(),
                    ticks: by_number.len(),
                    not_in_log: missing_in_log,
                    without_image: missing_frames,
                });
            }
            Ok(numbers
                .iter()
                .map(|&n| by_number[in_log(n).unwrap_or_default()].1)
                .collect())
        }
    }
}

/// The ball followed through a sequence: each frame's number and fix, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Followed {
    /// `(frame number, fix)` per frame.
    pub fixes: Vec<(u64, BallFix)>,
    /// Frame size, px.
    pub frame_size: (u32, u32),
}

/// Follow the ball frame to frame through `seq` inside `roi` (the whole frame when `None`):
/// each search starts from the position predicted by the last two fixes (constant velocity)
/// and accepts only objects within two ball radii of it, so a second bright object elsewhere
/// cannot take the ball's place; after more than three frames without a fix the whole region
/// is searched again.
pub fn follow_ball(
    seq: &ImageSequence,
    finder: &BallFinder,
    roi: Option<Roi>,
) -> Result<Followed, TrackError> {
    let gate = 2.0 * finder.radius_px;
    let mut fixes = Vec::with_capacity(seq.len());
    let mut region: Option<Roi> = None;
    let mut frame_size = (0, 0);
    // The last two measured positions: (frame number, x, y).
    let mut last: Vec<(u64, f64, f64)> = Vec::with_capacity(2);
    for item in seq.frames() {
        let f = item?;
        let region = *region.get_or_insert_with(|| {
            frame_size = (f.frame.width(), f.frame.height());
            roi.unwrap_or(Roi {
                x: 0,
                y: 0,
                width: f.frame.width(),
                height: f.frame.height(),
            })
        });
        if !region.fits(f.frame.width(), f.frame.height()) {
            return Err(TrackError::RoiOutside {
                roi: region,
                frame: (f.frame.width(), f.frame.height()),
                sequence: f.source.to_string(),
            });
        }
        let prediction = match last.as_slice() {
            [.., (n1, _, _)] if f.number - n1 > LOST_AFTER_FRAMES => None,
            [(n0, x0, y0), (n1, x1, y1)] => {
                let k = (f.number - n1) as f64 / (n1 - n0).max(1) as f64;
                Some((x1 + (x1 - x0) * k, y1 + (y1 - y0) * k))
            }
            [(_, x, y)] => Some((*x, *y)),
            _ => None,
        };
        let fix = finder.find(&f.frame, region, prediction, gate);
        if fix.status == FixStatus::Ok {
            if last.len() == 2 {
                last.remove(0);
            }
            last.push((f.number, fix.x_px, fix.y_px));
        }
        fixes.push((f.number, fix));
    }
    Ok(Followed { fixes, frame_size })
}

/// Check a tracking spec's numbers.
pub fn check_spec(spec: &TrackSpec) -> Result<(), TrackError> {
    let positive = |flag: &'static str, value: f64| {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(TrackError::NotPositive { flag, value })
        }
    };
    positive("--m-per-px", spec.m_per_px)?;
    positive("--ball-diameter", spec.ball_diameter_m)?;
    positive("--apex-window", spec.apex_window_s)?;
    if !(spec.exposure_s.is_finite() && spec.exposure_s >= 0.0) {
        return Err(TrackError::Exposure(spec.exposure_s));
    }
    if spec.rest_frames == 0 {
        return Err(TrackError::NoRestFrames);
    }
    Ok(())
}

/// Track the ball through `seq` and measure the jump.
pub fn track_sequence(
    seq: &ImageSequence,
    spec: &TrackSpec,
    clock: &FrameClock,
) -> Result<TrackResult, TrackError> {
    check_spec(spec)?;
    let numbers = seq.numbers();
    let trigger_times = frame_times(&numbers, clock)?;
    let finder = BallFinder::new(spec.ball_diameter_m, spec.m_per_px);
    let followed = follow_ball(seq, &finder, spec.roi)?;
    let frame_size = followed.frame_size;
    let mut frames: Vec<TrackedFrame> = followed
        .fixes
        .into_iter()
        .enumerate()
        .map(|(i, (number, fix))| TrackedFrame {
            frame: number,
            t_s: trigger_times[i] + 0.5 * spec.exposure_s,
            x_px: fix.x_px,
            y_px: fix.y_px,
            rod_height_m: f64::NAN,
            status: fix.status,
            reason: fix.reason,
        })
        .collect();
    // Rest: before the log's first RUNNING sample, else the first rest_frames frames.
    let (rest_idx, rest_rule): (Vec<usize>, String) = match clock {
        FrameClock::Log {
            running_from_s: Some(t0),
            ..
        } => (
            (0..frames.len())
                .filter(|&i| trigger_times[i] < *t0)
                .collect(),
            format!("frames before the log's first RUNNING sample (t = {t0} s)"),
        ),
        _ => (
            (0..frames.len().min(spec.rest_frames)).collect(),
            format!("the first {} frames", spec.rest_frames),
        ),
    };
    let mut rest_y: Vec<f64> = rest_idx
        .iter()
        .filter(|&&i| frames[i].status == FixStatus::Ok)
        .map(|&i| frames[i].y_px)
        .collect();
    if rest_y.is_empty() {
        return Err(TrackError::RestUnmeasured {
            rest_frames: rest_idx.len(),
            rule: rest_rule,
        });
    }
    rest_y.sort_by(f64::total_cmp);
    let m = rest_y.len();
    let rest_height_px = if m % 2 == 1 {
        rest_y[m / 2]
    } else {
        0.5 * (rest_y[m / 2 - 1] + rest_y[m / 2])
    };
    let mut flagged = FlagCounts::default();
    for f in &mut frames {
        match f.status {
            FixStatus::Ok => f.rod_height_m = (rest_height_px - f.y_px) * spec.m_per_px,
            FixStatus::Missing => flagged.missing += 1,
            FixStatus::Clipped => flagged.clipped += 1,
            FixStatus::Ambiguous => flagged.ambiguous += 1,
        }
    }
    let apex = fit_apex(&frames, spec.apex_window_s).ok_or(TrackError::NeverMeasured)?;
    Ok(TrackResult {
        frames,
        rest_height_px,
        rest_frames_used: m,
        rest_rule,
        apex,
        flagged,
        frame_size,
    })
}

/// The apex of the measured heights: a least-squares parabola through the frames within
/// `window_s` of the highest frame (at least 5 frames and a downward curvature), else the
/// highest frame. `None` if no frame was measured.
pub fn fit_apex(frames: &[TrackedFrame], window_s: f64) -> Option<Apex> {
    let top = frames
        .iter()
        .filter(|f| f.status == FixStatus::Ok)
        .max_by(|a, b| a.rod_height_m.total_cmp(&b.rod_height_m))?;
    let near: Vec<(f64, f64)> = frames
        .iter()
        .filter(|f| f.status == FixStatus::Ok && (f.t_s - top.t_s).abs() <= window_s)
        .map(|f| (f.t_s - top.t_s, f.rod_height_m))
        .collect();
    let sampled = Apex {
        jump_height_m: top.rod_height_m,
        apex_time_s: top.t_s,
        method: "highest_frame",
        highest_frame_height_m: top.rod_height_m,
        highest_frame_time_s: top.t_s,
        fitted_accel_m_s2: None,
        fit_frames: 0,
        fit_residual_rms_m: None,
    };
    if near.len() < 5 {
        return Some(sampled);
    }
    let mut m = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    for &(t, h) in &near {
        let basis = [1.0, t, t * t];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += basis[i] * basis[j];
            }
            r[i] += basis[i] * h;
        }
    }
    let Some([a, b, c]) = solve3(m, r) else {
        return Some(sampled);
    };
    let t_vertex = -b / (2.0 * c);
    if c >= 0.0 || t_vertex.abs() > window_s {
        return Some(sampled);
    }
    let rms = (near
        .iter()
        .map(|&(t, h)| (a + b * t + c * t * t - h).powi(2))
        .sum::<f64>()
        / near.len() as f64)
        .sqrt();
    Some(Apex {
        jump_height_m: a - b * b / (4.0 * c),
        apex_time_s: top.t_s + t_vertex,
        method: "parabola",
        fitted_accel_m_s2: Some(2.0 * c),
        fit_frames: near.len(),
        fit_residual_rms_m: Some(rms),
        ..sampled
    })
}

/// The frames' clock from a log: its camera rows and its first RUNNING sample.
pub fn log_clock(log: &AcqLog) -> FrameClock {
    FrameClock::Log {
        frames: log
            .rows
            .iter()
            .filter_map(|r| r.camera_frame.map(|n| (n, r.t_s)))
            .collect(),
        running_from_s: log
            .rows
            .iter()
            .find(|r| r.flags.is_some_and(|f| f & u32::from(flags::RUNNING) != 0))
            .map(|r| r.t_s),
    }
}
