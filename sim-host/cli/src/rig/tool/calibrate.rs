//! The drive's DAC calibration from the host: `rig calibrate-drive` measures nothing itself
//! (the lab measures the drive's input voltage with the drive disabled, `docs/bringup.md`); it
//! sends the codes found (`SetDriveCalibration`, checked by the core) and saves them in a file.
//! Every `rig` command given `--drive-calibration FILE` sends that file's codes when it opens
//! the session, so the calibration is stored on the host and the board is given it each time
//! (the board keeps it until it resets).
//!
//! The file (TOML): `zero_code = 2101` (the DAC code at which the drive reads 0 V) and
//! `codes_per_newton = 6.48` (DAC codes per newton of force command).

use std::path::{Path, PathBuf};

use clap::Args;

use super::session::query_status;
use super::{TargetArgs, link_failed};
use sandjumper_core::{Command, DriveCalibration};
use sandjumper_output::CliError;
use sandjumper_rig::hil::link::RigLink;
use sandjumper_rig::hil::rig_model::RigModelConfig;

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

/// Read and check a calibration file: the file, the key and what is allowed on error.
pub fn read_calibration(path: &Path) -> Result<DriveCalibration, CliError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        CliError::input(format!(
            "cannot read the drive calibration `{}`: {e}",
            path.display()
        ))
    })?;
    let cal: DriveCalibration = toml::from_str(&text).map_err(|e| {
        CliError::input(format!(
            "drive calibration `{}`: {e} (allowed: zero_code = CODE, codes_per_newton = X)",
            path.display()
        ))
    })?;
    cal.validate()
        .map_err(|e| CliError::input(format!("drive calibration `{}`: {e}", path.display())))?;
    Ok(cal)
}

/// Send `cal` to the controller (it refuses while the drive is enabled).
pub fn send_calibration(link: &mut dyn RigLink, cal: DriveCalibration) -> Result<(), CliError> {
    let name = link.name();
    link.command(&Command::SetDriveCalibration(cal))
        .map_err(|e| link_failed(&name, "setting the drive calibration", e))?;
    Ok(())
}

/// Run `rig calibrate-drive`.
pub fn run(a: &CalibrateDriveArgs) -> Result<(), CliError> {
    let cal = DriveCalibration {
        zero_code: a.zero_code,
        codes_per_newton: a.codes_per_newton,
    };
    cal.validate()
        .map_err(|e| CliError::input(format!("--zero-code/--codes-per-newton: {e}")))?;
    let mut link = a.target.open(&RigModelConfig::default())?;
    let name = link.name();
    send_calibration(link.as_mut(), cal)?;
    let status = query_status(link.as_mut()).map_err(|e| link_failed(&name, "status query", e))?;
    link.finish()
        .map_err(|e| link_failed(&name, "closing the session", e))?;
    if let Some(path) = &a.save {
        let text = toml::to_string(&cal)
            .map_err(|e| CliError::internal(format!("cannot encode the calibration: {e}")))?;
        std::fs::write(path, text)
            .map_err(|e| CliError::input(format!("cannot write `{}`: {e}", path.display())))?;
    }
    let c = status.drive_calibration;
    println!(
        "drive calibration on {name}: zero code {}, {} codes/N (0 N -> code {}, +300 N -> {}, -300 N -> {})",
        c.zero_code,
        c.codes_per_newton,
        c.force_to_code(0.0),
        c.force_to_code(300.0),
        c.force_to_code(-300.0)
    );
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
    let mut link = a.target.open(&RigModelConfig::default())?;
    let name = link.name();
    let before = query_status(link.as_mut()).map_err(|e| link_failed(&name, "status query", e))?;
    link.command(&Command::AcknowledgeReset)
        .map_err(|e| link_failed(&name, "acknowledging the reset", e))?;
    link.finish()
        .map_err(|e| link_failed(&name, "closing the session", e))?;
    println!(
        "reset ({:?}) acknowledged on {name}: Arm is allowed",
        before.reset_cause
    );
    Ok(())
}
