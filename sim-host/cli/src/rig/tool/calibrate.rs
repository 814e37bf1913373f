//! `sandjumper rig calibrate-drive` and `rig acknowledge-reset`: faces over
//! [`sandjumper_rig::tool::calibrate`] (the calibration file's format is described there).

use std::path::PathBuf;

use clap::Args;

use super::TargetArgs;
use crate::command::CliError;
use sandjumper_output::Silent;
use sandjumper_rig::tool::calibrate::{self as lib, CalibrateRequest};

/// `rig calibrate-drive`.
#[derive(Debug, Clone, Args)]
pub struct CalibrateDriveArgs {
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// DAC code at which the drive's force input reads 0 V (nominal 2048).
    #[arg(long, value_name = "CODE")]
    pub zero_code: u16,
    /// DAC codes per newton of force command (nominal 2047 / 300 N = 6.823).
    #[arg(long, value_name = "CODES_PER_N")]
    pub codes_per_newton: f32,
    /// Save the codes in FILE (TOML) for `--drive-calibration FILE` of later `rig` commands.
    #[arg(long, value_name = "FILE.toml")]
    pub save: Option<PathBuf>,
}

/// Run `rig calibrate-drive`.
pub fn run(a: &CalibrateDriveArgs) -> Result<(), CliError> {
    let request = CalibrateRequest {
        target: a.target.target(),
        zero_code: a.zero_code,
        codes_per_newton: a.codes_per_newton,
        save: a.save.clone(),
    };
    print!("{}", lib::calibrate(&request, &Silent)?);
    Ok(())
}

/// `rig acknowledge-reset`.
#[derive(Debug, Clone, Args)]
pub struct AcknowledgeResetArgs {
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
}

/// Run `rig acknowledge-reset`: after a reset other than power-on the board refuses `Arm`
/// until the carriage's position has been checked and this is sent.
pub fn acknowledge_reset(a: &AcknowledgeResetArgs) -> Result<(), CliError> {
    print!("{}", lib::acknowledge_reset(&a.target.target(), &Silent)?);
    Ok(())
}
