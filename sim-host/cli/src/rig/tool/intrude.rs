//! `sandjumper rig intrude`: the slow-intrusion program (the paper's `F_p(z)` measurement); a
//! face over [`sandjumper_rig::tool::intrude`], where the program and its curves are described.

use std::path::PathBuf;

use clap::Args;

use super::{RigParamArgs, TargetArgs};
use crate::command::CliError;
use crate::rig::face::run_program;
use sandjumper_core::intrusion::{MAX_HOLD_S, MAX_INTRUSION_SPEED_M_S};
use sandjumper_rig::tool::intrude::{IntrudeRequest, parse_bounded};

/// `rig intrude`.
#[derive(Debug, Clone, Args)]
pub struct IntrudeArgs {
    /// The live view of the run.
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// Motor position p where the foot touches the free surface (the program starts and ends
    /// here), m.
    #[arg(long, value_name = "M", default_value = "-0.02", allow_hyphen_values = true,
          value_parser = parse_bounded("start position (m)", -0.025, 0.025))]
    pub start: f64,
    /// First intrusion depth below the surface, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true, default_value = "0.02", value_parser = parse_bounded("depth (m)", 0.0, 0.05))]
    pub depth: f64,
    /// How far the rod is pulled back up after the first hold, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true, default_value = "0.005", value_parser = parse_bounded("withdrawal (m)", 0.0, 0.05))]
    pub withdraw: f64,
    /// Depth the re-intrusion goes to, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true, default_value = "0.03", value_parser = parse_bounded("re-intrusion depth (m)", 0.0, 0.05))]
    pub reintrusion_depth: f64,
    /// Intrusion speed, m/s.
    #[arg(long, value_name = "M/S", allow_negative_numbers = true, default_value = "0.01",
          value_parser = parse_bounded("speed (m/s)", 0.0, MAX_INTRUSION_SPEED_M_S))]
    pub speed: f64,
    /// Each hold, s.
    #[arg(long, value_name = "S", allow_negative_numbers = true, default_value = "0.5", value_parser = parse_bounded("hold (s)", 0.0, MAX_HOLD_S))]
    pub hold: f64,
    /// Depth bin of the force-vs-depth curves, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true, default_value = "0.00025", value_parser = parse_bounded("bin (m)", 1e-6, 0.005))]
    pub bin: f64,
    /// Simulated rig and parameters (masses and force constant to interpret the current).
    #[command(flatten)]
    pub rig: RigParamArgs,
    /// Write intrusion.csv, reintrusion.csv, acquisition.csv, params.toml, summary.json,
    /// intrusion.png and intrusion.svg into DIR.
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

/// Run `rig intrude`.
pub fn run(a: &IntrudeArgs) -> Result<(), CliError> {
    let request = IntrudeRequest {
        target: a.target.target(),
        start_m: a.start,
        depth_m: a.depth,
        withdraw_m: a.withdraw,
        reintrusion_depth_m: a.reintrusion_depth,
        speed_m_s: a.speed,
        hold_s: a.hold,
        bin_m: a.bin,
        model: a.rig.model(),
        params: a.rig.resolve()?,
    };
    run_program(&request, &a.live, (&a.out, a.mcap, a.json))
}
