//! `sandjumper rig`: the host tool for the rig's board (`--port PATH`) or a simulated
//! controller (`--link sil|pil|f407`); each subcommand is a face over its typed call in
//! [`sandjumper_rig::tool`], where the programs are described.

pub mod calibrate;
pub mod flash;
pub mod intrude;
pub mod jump;
pub mod replay;
pub mod status;

use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};

use crate::command::CliError;
use crate::command::args::ModelArg;
use crate::command::resolve::{ParamsFile, resolve_params};
use sandjumper_model::params::{ModelName, Params};
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::tool::target::{Target, parse_board_pace};

/// `sandjumper rig`.
#[derive(Debug, Clone, Args)]
pub struct RigArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: RigCommand,
}

/// The rig subcommands.
#[derive(Debug, Clone, Subcommand)]
pub enum RigCommand {
    /// Write the firmware to the board with the probe-rs CLI (nothing to do for sil/pil).
    Flash(flash::FlashArgs),
    /// Print the controller's state, fault and counters (--json for JSON).
    Status(status::StatusArgs),
    /// Configure, arm and run one jump; write its acquisition log, summary and figure.
    Jump(jump::JumpArgs),
    /// Run the slow-intrusion program; write force-vs-depth CSVs (input of `fit intrusion`),
    /// the acquisition log and a figure.
    Intrude(intrude::IntrudeArgs),
    /// Upload an acquisition log's (edited) motor trajectory, verify it, run it and record the
    /// new log.
    Replay(replay::ReplayArgs),
    /// Send the DAC codes of the drive's force command measured at bring-up (drive off), and
    /// save them for --drive-calibration.
    CalibrateDrive(calibrate::CalibrateDriveArgs),
    /// Allow Arm again after a reset other than power-on (the carriage's position checked).
    AcknowledgeReset(calibrate::AcknowledgeResetArgs),
}

/// A simulated controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SimLink {
    /// The core's controller in this process.
    Sil,
    /// The real firmware in QEMU mps2-an386 (frames over semihosting FIFOs).
    Pil,
    /// The F407 release ELF (the binary a board is flashed with) on the virtual board, the
    /// robot coupled through its peripherals; built separately (sim-host/virtual-f407/build.sh).
    F407,
}

/// Which controller: a board on a serial port, or a simulated one (exactly one of the two).
#[derive(Debug, Clone, Args)]
#[group(id = "controller", required = true, multiple = false)]
pub struct ControllerArgs {
    /// The board's USB serial port (e.g. /dev/ttyACM0): the real rig.
    #[arg(long, value_name = "PATH")]
    pub port: Option<String>,
    /// A simulated controller against a simulated rig instead of a board.
    #[arg(long, value_enum)]
    pub link: Option<SimLink>,
}

/// The controller and its firmware.
#[derive(Debug, Clone, Args)]
pub struct TargetArgs {
    /// `--port PATH` or `--link sil|pil|f407`.
    #[command(flatten)]
    pub controller: ControllerArgs,
    /// Firmware ELF: for --link pil the QEMU build (--features board-qemu); for --link f407
    /// and `flash` the F407 build.
    #[arg(long, value_name = "ELF")]
    pub firmware: Option<PathBuf>,
    /// The virtual board's program for --link f407 (default:
    /// sim-host/virtual-f407/target/release/virtual-f407).
    #[arg(long, value_name = "PATH")]
    pub virtual_board: Option<PathBuf>,
    /// Run the virtual board of --link f407 no faster than X times real time (0.001..=1: only
    /// slower, since the host polls every 50 ms of wall time and the board's 500 ms watchdogs
    /// count its virtual time;
    /// default: as fast as the machine allows). The host counts its waits in the board's
    /// virtual time, so a slow board runs the same program.
    #[arg(long, value_name = "X", value_parser = parse_board_pace)]
    pub board_pace: Option<f64>,
    /// Drive calibration saved by `rig calibrate-drive --save`: sent when the session opens.
    #[arg(long, value_name = "FILE.toml")]
    pub drive_calibration: Option<PathBuf>,
}

impl TargetArgs {
    /// The library's target (its link `Serial` for `--port`).
    pub fn target(&self) -> Target {
        let link = match (&self.controller.port, self.controller.link) {
            (Some(p), _) => LinkArg::Serial(p.clone()),
            (None, Some(SimLink::Pil)) => LinkArg::Pil,
            (None, Some(SimLink::F407)) => LinkArg::F407,
            _ => LinkArg::Sil,
        };
        Target {
            link,
            firmware: self.firmware.clone(),
            virtual_board: self.virtual_board.clone(),
            board_pace: self.board_pace,
            drive_calibration: self.drive_calibration.clone(),
        }
    }
}

/// The simulated rig (for sil/pil) and the parameters used to interpret measurements.
#[derive(Debug, Clone, Args)]
pub struct RigParamArgs {
    /// Ground model of the simulated sand (sil/pil).
    #[arg(long, value_enum, default_value = "eq4")]
    pub model: ModelArg,
    /// Packing fraction phi of the simulated sand (presets 0.57..=0.62).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = crate::command::args::parse_phi)]
    pub phi: f64,
    /// TOML file overriding any parameter (as for `sandjumper jump --params`): the simulated
    /// rig's, and the masses, force constant and peak force used to interpret a board's data.
    #[arg(long, value_name = "FILE.toml")]
    pub params: Option<PathBuf>,
}

impl RigParamArgs {
    /// Resolved parameters.
    pub fn resolve(&self) -> Result<Params, CliError> {
        let file = ParamsFile::read_opt(self.params.as_deref())?;
        resolve_params(self.phi, file.as_ref())
    }

    /// The ground model.
    pub fn model(&self) -> ModelName {
        self.model.into()
    }
}

/// Run `rig`.
pub fn run(a: &RigArgs) -> Result<(), CliError> {
    match &a.command {
        RigCommand::Flash(f) => flash::run(f),
        RigCommand::Status(s) => status::run(s),
        RigCommand::Jump(j) => jump::run(j),
        RigCommand::Intrude(i) => intrude::run(i),
        RigCommand::Replay(r) => replay::run(r),
        RigCommand::CalibrateDrive(c) => calibrate::run(c),
        RigCommand::AcknowledgeReset(a) => calibrate::acknowledge_reset(a),
    }
}
