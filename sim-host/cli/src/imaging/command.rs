//! `sandjumper track FRAMES`: the rod's ball tracked through a camera's frames, and the jump
//! height measured the paper's way; `sandjumper camera-scale FRAMES --log LOG`: the camera's
//! metres per pixel from a slow motor move and the encoder. The runs are
//! `sandjumper_imaging::run` and `sandjumper_imaging::camera_scale`; this is their face.

use std::path::PathBuf;

use clap::Args;

use super::camera_scale::ScaleRequest;
use super::frame::Roi;
use super::run::{
    TrackRequest, parse_exposure, parse_fps, parse_length, parse_m_per_px, parse_roi, parse_seconds,
};
use crate::command::CliError;
use crate::command::progress::Bars;

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

/// `sandjumper camera-scale`.
#[derive(Debug, Clone, Args)]
pub struct CameraScaleArgs {
    /// The move.
    #[command(flatten)]
    pub request: ScaleRequest,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

impl TrackArgs {
    /// The request these arguments make.
    pub fn request(&self) -> TrackRequest {
        TrackRequest {
            frames: self.frames.clone(),
            m_per_px: self.m_per_px,
            fps: self.fps,
            log: self.log.clone(),
            roi: self.roi,
            ball_diameter_m: self.ball_diameter,
            rest_frames: self.rest_frames as usize,
            exposure_s: self.exposure,
            apex_window_s: self.apex_window,
        }
    }
}

/// Run `sandjumper track`: `--out` written (then `wrote DIR`), the notes, the summary.
pub fn run(a: &TrackArgs) -> Result<(), CliError> {
    let progress = Bars::holding();
    let request = a.request();
    let (outcome, written) = match a.out.as_deref() {
        Some(out) => super::run::run_into(&request, out, &progress).map(|(o, d)| (o, Some(d)))?,
        None => (super::run::run(&request, &progress)?, None),
    };
    progress.release(written.as_deref());
    crate::command::print_outcome(a.json, &outcome, || outcome.summary_json())
}

/// Run `sandjumper camera-scale`.
pub fn run_scale(a: &CameraScaleArgs) -> Result<(), CliError> {
    let progress = Bars::holding();
    let outcome = super::camera_scale::run(&a.request, &progress)?;
    crate::command::print_outcome(a.json, &outcome, || outcome.summary_json())?;
    progress.release(None);
    Ok(())
}
