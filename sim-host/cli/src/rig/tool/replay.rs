//! `sandjumper rig replay LOG` / `rig replay --stroke stroke.csv`: run a recorded (or edited)
//! motor trajectory, or a stroke file, on the rig; a face over
//! [`sandjumper_rig::tool::replay`], where the editing, the feasibility check and the upload
//! are described.

use std::path::PathBuf;

use clap::Args;

use super::{RigParamArgs, TargetArgs};
use crate::command::CliError;
use crate::rig::face::run_program;
use sandjumper_rig::tool::replay::Clip;
use sandjumper_rig::tool::replay::{ReplayRequest, ReplaySource, parse_clip, parse_factor};

/// `rig replay`.
#[derive(Debug, Clone, Args)]
pub struct ReplayArgs {
    /// The live view of the run.
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
    /// The acquisition log whose encoder record is replayed.
    #[arg(
        value_name = "LOG.csv",
        required_unless_present = "stroke",
        conflicts_with = "stroke"
    )]
    pub log: Option<PathBuf>,
    /// Replay a stroke file instead of a log: `t_s,p_m` rows at a fixed rate (what
    /// `sandjumper optimize` writes as stroke.csv; a replay's table.csv is one too).
    #[arg(long, value_name = "FILE")]
    pub stroke: Option<PathBuf>,
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// Multiply the positions by X (about mid-stroke p = 0).
    #[arg(long, value_name = "X", allow_negative_numbers = true, default_value = "1", value_parser = parse_factor("scale"))]
    pub scale: f64,
    /// Stretch time by X (above 1: slower).
    #[arg(long, value_name = "X", allow_negative_numbers = true, default_value = "1", value_parser = parse_factor("time stretch"))]
    pub time_stretch: f64,
    /// Replay only START:END, seconds from the log's first sample (before stretching).
    #[arg(long, value_name = "START:END", value_parser = parse_clip)]
    pub clip: Option<Clip>,
    /// Samples per second of the uploaded table (divides the 10 kHz control rate; default
    /// 1000 for a log, the file's own rate for --stroke).
    #[arg(long, value_name = "HZ", value_parser = clap::value_parser!(u32).range(10..=10_000))]
    pub table_rate: Option<u32>,
    /// Accept a log with gaps (interpolated).
    #[arg(long)]
    pub allow_gaps: bool,
    /// Simulated rig and parameters (motor mass and peak force for the force check).
    #[command(flatten)]
    pub rig: RigParamArgs,
    /// Write acquisition.csv (the new log), table.csv (what was uploaded), params.toml,
    /// summary.json, replay.png and replay.svg into DIR.
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

impl ReplayArgs {
    /// The library's request: the parameters resolved, the source read.
    pub fn request(&self) -> Result<ReplayRequest, CliError> {
        let params = self.rig.resolve()?;
        let (source, source_name) =
            ReplaySource::read(self.log.as_deref(), self.stroke.as_deref(), self.allow_gaps)?;
        Ok(ReplayRequest {
            target: self.target.target(),
            source,
            source_name,
            scale: self.scale,
            time_stretch: self.time_stretch,
            clip: self.clip,
            table_rate_hz: self.table_rate,
            model: self.rig.model(),
            params,
        })
    }
}

/// Run `rig replay`.
pub fn run(a: &ReplayArgs) -> Result<(), CliError> {
    run_program(&a.request()?, &a.live, (&a.out, a.mcap, a.json))
}
