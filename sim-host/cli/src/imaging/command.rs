//! `sandjumper track FRAMES`: the rod's ball tracked through a camera's frames, and the jump
//! height measured the paper's way; `sandjumper camera-scale FRAMES --log LOG`: the camera's
//! metres per pixel from a slow motor move and the encoder.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::ball::{BallFinder, FixStatus};
use super::figure::{figure, thumbnail};
use super::frame::Roi;
use super::scale::{ScaleFit, fit_scale};
use super::sequence::ImageSequence;
pub use super::track::log_clock;
use super::track::{
    Apex, CSV_HEADER, FlagCounts, FrameClock, TrackError, TrackResult, TrackSpec, follow_ball,
    track_sequence,
};
use crate::command::args::parse_positive_as;
use sandjumper_acqlog::{AcqLog, Column, ReadOptions};
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_output::plot::save_figure;

fn parse_m_per_px(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a scale in metres per pixel")
}

fn parse_fps(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a frame rate in frames/s")
}

fn parse_length(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a length in metres")
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a time in seconds")
}

fn parse_exposure(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not an exposure time: seconds >= 0")),
    }
}

fn parse_px(s: &str) -> Result<f64, String> {
    parse_positive_as(s, "a diameter in pixels")
}

/// `X,Y,W,H` in pixels.
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

/// `sandjumper track`.
#[derive(Debug, Clone, Args)]
#[command(group(clap::ArgGroup::new("clock").required(true).args(["fps", "log"])))]
pub struct TrackArgs {
    /// The frames: a directory (ordered by the number in each file name), a glob such as
    /// 'run3/*.png' (quoted), or a multi-page TIFF. PNG, TIFF, BMP; 8/16-bit grey or RGB.
    #[arg(value_name = "FRAMES")]
    pub frames: String,
    /// Scale, metres per pixel (`sandjumper camera-scale` measures it).
    #[arg(long, value_name = "M", value_parser = parse_m_per_px)]
    pub m_per_px: f64,
    /// Frame rate, frames/s (frame times from the numbers in the file names).
    #[arg(long, value_name = "FPS", value_parser = parse_fps)]
    pub fps: Option<f64>,
    /// The acquisition log whose `camera_frame` rows time the frames (and whose first
    /// RUNNING sample ends the rest frames); with --out, written again with `rod_height_m`.
    #[arg(long, value_name = "ACQ.csv")]
    pub log: Option<PathBuf>,
    /// Region of interest X,Y,W,H, px: only the ball inside counts.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_roi)]
    pub roi: Option<Roi>,
    /// Ball diameter, m.
    #[arg(long, value_name = "M", default_value = "0.0095", value_parser = parse_length)]
    pub ball_diameter: f64,
    /// Rest frames when the log does not say when the trajectory started (the first N).
    #[arg(long, value_name = "N", default_value = "10", value_parser = clap::value_parser!(u32).range(1..))]
    pub rest_frames: u32,
    /// Exposure time, s: each frame's time is its trigger plus half of it.
    #[arg(long, value_name = "S", default_value = "0", value_parser = parse_exposure)]
    pub exposure: f64,
    /// Half-width of the apex parabola's window, s.
    #[arg(long, value_name = "S", default_value = "0.02", value_parser = parse_seconds)]
    pub apex_window: f64,
    /// Write track.csv, summary.json, track.toml, track.png/.svg (and acquisition.csv with
    /// --log) into DIR.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
}

/// `summary.json` of `track`.
#[derive(Debug, Serialize)]
pub struct TrackReport<'a> {
    /// Jump height: the apex parabola's vertex (or the highest frame), m.
    pub jump_height_m: f64,
    /// Its time, s.
    pub apex_time_s: f64,
    /// The apex in full.
    pub apex: &'a Apex,
    /// Ball centre's row at rest, px.
    pub rest_height_px: f64,
    /// Frames the rest height came from, and how they were chosen.
    pub rest_frames: usize,
    /// The rule.
    pub rest_rule: &'a str,
    /// Frames read.
    pub frames: usize,
    /// Frames flagged (missing, clipped or ambiguous: never filled in).
    pub frames_flagged: usize,
    /// By reason.
    pub flagged: &'a FlagCounts,
    /// Scale, m/px.
    pub m_per_px: f64,
    /// `fps` or `log`.
    pub time_source: &'static str,
    /// Frame size, px.
    pub frame_size: (u32, u32),
    /// The resolved options.
    pub spec: &'a TrackSpec,
}

fn input(e: impl std::fmt::Display) -> CliError {
    CliError::input(e.to_string())
}

fn read_log(path: &std::path::Path) -> Result<AcqLog, CliError> {
    AcqLog::read_file(path, &ReadOptions::default())
        .map_err(|e| CliError::input(format!("--log {}: {e}", path.display())))
}

/// Run `sandjumper track`.
pub fn run(a: &TrackArgs) -> Result<(), CliError> {
    crate::command::print_analysed(&analyse(a)?, a.json);
    Ok(())
}

/// Track the frames `a` names (writing `--out` if given) without printing the summary.
pub fn analyse(a: &TrackArgs) -> Result<sandjumper_output::Analysed, CliError> {
    let seq = ImageSequence::open(&a.frames).map_err(|e| input(format!("frames: {e}")))?;
    let log = a.log.as_deref().map(read_log).transpose()?;
    let clock = match (&log, a.fps) {
        (Some(log), _) => log_clock(log),
        (None, Some(fps)) => FrameClock::Fps(fps),
        (None, None) => return Err(input("give --fps or --log to time the frames")),
    };
    let spec = TrackSpec {
        m_per_px: a.m_per_px,
        ball_diameter_m: a.ball_diameter,
        roi: a.roi,
        rest_frames: a.rest_frames as usize,
        apex_window_s: a.apex_window,
        exposure_s: a.exposure,
    };
    let staged = a.out.as_deref().map(StagedDir::create).transpose()?;
    let result = track_sequence(&seq, &spec, &clock).map_err(|e: TrackError| input(e))?;
    let report = TrackReport {
        jump_height_m: result.apex.jump_height_m,
        apex_time_s: result.apex.apex_time_s,
        apex: &result.apex,
        rest_height_px: result.rest_height_px,
        rest_frames: result.rest_frames_used,
        rest_rule: &result.rest_rule,
        frames: result.frames.len(),
        frames_flagged: result.frames_flagged(),
        flagged: &result.flagged,
        m_per_px: a.m_per_px,
        time_source: if log.is_some() { "log" } else { "fps" },
        frame_size: result.frame_size,
        spec: &spec,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary: {e}")))?;
    if let Some(staged) = staged {
        write_outputs(&staged, a, &seq, &result, log, &spec, &json)?;
        let dir = staged.commit()?;
        eprintln!("wrote {}", dir.display());
    }
    if result.frames_flagged() > 0 {
        eprintln!(
            "warning: {} of {} frames flagged (missing {}, clipped {}, ambiguous {}); see track.csv's reason column",
            result.frames_flagged(),
            result.frames.len(),
            result.flagged.missing,
            result.flagged.clipped,
            result.flagged.ambiguous
        );
    }
    let human = human(&report);
    Ok(sandjumper_output::Analysed { json, human })
}

fn human(r: &TrackReport<'_>) -> String {
    let mm = |v: f64| format!("{:.3} mm", 1e3 * v);
    let a = r.apex;
    let mut t = format!(
        "track: {} frames ({} flagged), time from {}\n",
        r.frames, r.frames_flagged, r.time_source
    );
    t += &format!(
        "  jump height        {}  ({} at t = {:.4} s)\n",
        mm(a.jump_height_m),
        a.method,
        a.apex_time_s
    );
    t += &format!(
        "  highest frame      {}  (t = {:.4} s)\n",
        mm(a.highest_frame_height_m),
        a.highest_frame_time_s
    );
    if let (Some(acc), Some(rms)) = (a.fitted_accel_m_s2, a.fit_residual_rms_m) {
        t += &format!(
            "  apex fit           {} frames, acceleration {acc:.2} m/s^2, residual RMS {:.1} um\n",
            a.fit_frames,
            1e6 * rms
        );
    }
    t += &format!(
        "  rest               row {:.3} px (median of {} frames: {})\n",
        r.rest_height_px, r.rest_frames, r.rest_rule
    );
    t += &format!("  scale              {} m/px\n", r.m_per_px);
    t
}

fn write_outputs(
    staged: &StagedDir,
    a: &TrackArgs,
    seq: &ImageSequence,
    result: &TrackResult,
    log: Option<AcqLog>,
    spec: &TrackSpec,
    json: &str,
) -> Result<(), CliError> {
    write_track_csv(&staged.file("track.csv"), result)
        .map_err(|e| CliError::internal(format!("cannot write track.csv: {e}")))?;
    staged.write_text("summary.json", &format!("{json}\n"))?;
    let spec_toml = toml::to_string(spec)
        .map_err(|e| CliError::internal(format!("cannot encode the options: {e}")))?;
    staged.write_text(
        "track.toml",
        &format!(
            "# The resolved options of `sandjumper track {}`{}\n{spec_toml}",
            a.frames,
            match &a.log {
                Some(l) => format!(" --log {}", l.display()),
                None => format!(" --fps {}", a.fps.unwrap_or_default()),
            }
        ),
    )?;
    let top = result
        .frames
        .iter()
        .enumerate()
        .filter(|(_, f)| f.status == FixStatus::Ok)
        .max_by(|x, y| x.1.rod_height_m.total_cmp(&y.1.rod_height_m));
    let thumb = match top {
        Some((i, f)) => match seq.nth(i) {
            Some(Ok(sf)) => {
                let half = 1.4 * 0.5 * spec.ball_diameter_m / spec.m_per_px;
                Some(thumbnail(&sf.frame, f.frame, f.x_px, f.y_px, half))
            }
            _ => None,
        },
        None => None,
    };
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
    if let Some(mut log) = log {
        let heights: std::collections::HashMap<u64, f64> = result
            .frames
            .iter()
            .filter(|f| f.status == FixStatus::Ok)
            .map(|f| (f.frame, f.rod_height_m))
            .collect();
        log.columns = log.columns.with(Column::RodHeightM);
        for row in &mut log.rows {
            row.rod_height_m = row.camera_frame.and_then(|n| heights.get(&n).copied());
        }
        log.meta.measured_jump_height_m = Some(result.apex.jump_height_m);
        log.write_file(&staged.file("acquisition.csv"))
            .map_err(|e| CliError::internal(format!("cannot write acquisition.csv: {e}")))?;
    }
    Ok(())
}

/// `track.csv`: one row per frame; a flagged frame has empty position and height and its
/// reason.
pub fn write_track_csv(path: &std::path::Path, result: &TrackResult) -> Result<(), csv::Error> {
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

/// `sandjumper camera-scale`.
#[derive(Debug, Clone, Args)]
pub struct CameraScaleArgs {
    /// The frames of the slow move (as for `track`).
    #[arg(value_name = "FRAMES")]
    pub frames: String,
    /// The acquisition log of the move: its `camera_frame` rows give the encoder position of
    /// each frame.
    #[arg(long, value_name = "ACQ.csv")]
    pub log: PathBuf,
    /// The ball's diameter in the image, px (roughly: it sets which bright objects count).
    #[arg(long, value_name = "PX", value_parser = parse_px)]
    pub ball_px: f64,
    /// Region of interest X,Y,W,H, px.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_roi)]
    pub roi: Option<Roi>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// The JSON of `camera-scale`.
#[derive(Debug, Serialize)]
pub struct ScaleReport<'a> {
    /// The fit.
    #[serde(flatten)]
    pub fit: &'a ScaleFit,
    /// Frames read.
    pub frames: usize,
    /// Frames flagged (not in the fit).
    pub frames_flagged: usize,
}

/// Run `sandjumper camera-scale`.
pub fn run_scale(a: &CameraScaleArgs) -> Result<(), CliError> {
    let seq = ImageSequence::open(&a.frames).map_err(|e| input(format!("frames: {e}")))?;
    let log = read_log(&a.log)?;
    let (fit, frames, flagged) = scale_from(&seq, &log, a.ball_px, a.roi)?;
    let report = ScaleReport {
        fit: &fit,
        frames,
        frames_flagged: flagged,
    };
    if a.json {
        let json = serde_json::to_string_pretty(&report)
            .map_err(|e| CliError::internal(format!("cannot encode the result: {e}")))?;
        println!("{json}");
    } else {
        println!(
            "camera scale: {:.6e} m/px ({:.2} px/mm), {} frames ({} flagged), travel {:.2} mm, R^2 {:.6}, residual RMS {:.3} px",
            fit.m_per_px,
            1e-3 / fit.m_per_px,
            frames,
            flagged,
            1e3 * fit.travel_m,
            fit.r_squared,
            fit.residual_rms_px
        );
    }
    if !fit.direction_ok {
        eprintln!(
            "warning: the ball moved up in the image as p grew; with the carriage clamped it moves down. Was the rod clamped instead (the scale is still |slope|)?"
        );
    }
    Ok(())
}

/// Fit the scale of `seq` against `log`: `(fit, frames, frames flagged)`.
pub fn scale_from(
    seq: &ImageSequence,
    log: &AcqLog,
    ball_px: f64,
    roi: Option<Roi>,
) -> Result<(ScaleFit, usize, usize), CliError> {
    let clock = log_clock(log);
    super::track::frame_times(&seq.numbers(), &clock).map_err(input)?;
    let positions = log.positions_m();
    let p_of: std::collections::HashMap<u64, f64> = log
        .rows
        .iter()
        .zip(&positions)
        .filter_map(|(r, p)| r.camera_frame.map(|n| (n, *p)))
        .collect();
    let finder = BallFinder {
        radius_px: 0.5 * ball_px,
    };
    let followed = follow_ball(seq, &finder, roi).map_err(input)?;
    let pairs: Vec<(f64, f64)> = followed
        .fixes
        .iter()
        .filter(|(_, f)| f.status == FixStatus::Ok)
        .filter_map(|(n, f)| p_of.get(n).map(|p| (*p, f.y_px)))
        .collect();
    let flagged = followed.fixes.len() - pairs.len();
    let fit = fit_scale(&pairs).map_err(|e| input(format!("camera-scale: {e}")))?;
    Ok((fit, followed.fixes.len(), flagged))
}
