//! `sandjumper rig jump`: configure, arm and run one sine jump on the controller; a face over
//! [`sandjumper_rig::tool::jump`].

use std::path::PathBuf;

use clap::Args;

use super::{RigParamArgs, TargetArgs};
use crate::command::CliError;
use crate::command::args::{KindArg, parse_freq, parse_tau};
use crate::rig::face::run_program;
use sandjumper_rig::hil::camera::read_camera;
use sandjumper_rig::tool::jump::JumpRequest;

/// `rig jump`.
#[derive(Debug, Clone, Args)]
pub struct JumpArgs {
    /// The live view of the run.
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// Jump kind.
    #[arg(long, value_enum)]
    pub kind: KindArg,
    /// Forcing frequency f of the one-cycle sine, Hz.
    #[arg(long, value_name = "HZ", value_parser = parse_freq)]
    pub freq: f64,
    /// Delay of the delayed stutter, s (required with --kind delayed).
    #[arg(long, value_name = "S", value_parser = parse_tau, required_if_eq("kind", "delayed"))]
    pub tau: Option<f64>,
    /// Camera frame rate, frames/s (200 rod tracking, 500 PIV; 0 none).
    #[arg(long, value_name = "FPS", default_value = "200", value_parser = clap::value_parser!(u32).range(0..=5000))]
    pub camera_fps: u32,
    /// Simulated rig and parameters.
    #[command(flatten)]
    pub rig: RigParamArgs,
    /// The simulated rod camera (TOML; see `hil --camera`), for --link sil|pil.
    #[arg(long, value_name = "FILE.toml")]
    pub camera: Option<PathBuf>,
    /// Write acquisition.csv, params.toml, summary.json, jump.png and jump.svg into DIR
    /// (and, through a simulated rig with a camera rate, frames/: the rendered rod-camera
    /// frames and camera.toml).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Also write the acquisition log as acquisition.mcap (for Foxglove, Lichtblick and
    /// PlotJuggler; see `sandjumper log convert`).
    #[arg(long)]
    pub mcap: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

impl JumpArgs {
    /// The library's request (the parameters resolved; the camera read later).
    pub fn request(&self) -> Result<JumpRequest, CliError> {
        Ok(JumpRequest {
            tau_s: self.tau,
            camera_fps: self.camera_fps,
            model: self.rig.model(),
            params: self.rig.resolve()?,
            ..JumpRequest::new(self.target.target(), self.kind.into(), self.freq)
        })
    }
}

/// Run `rig jump`.
pub fn run(a: &JumpArgs) -> Result<(), CliError> {
    let mut request = a.request()?;
    request.validate()?;
    request.camera = read_camera(a.camera.as_deref())?;
    run_program(&request, &a.live, (&a.out, a.mcap, a.json))
}
