//! The drive's DAC calibration from the host: `rig calibrate-drive` measures nothing itself
//! (the lab measures the drive's input voltage with the drive disabled, `docs/bringup.md`); it
//! sends the codes found (`SetDriveCalibration`, checked by the core) and saves them in a file.
//! Every program given a [`Target::drive_calibration`] file sends that file's codes when it
//! opens the session, so the calibration is stored on the host and the board is given it each
//! time (the board keeps it until it resets). Also `rig acknowledge-reset`
//! ([`acknowledge_reset`]).
//!
//! The file (TOML): `zero_code = 2101` (the DAC code at which the drive reads 0 V) and
//! `codes_per_newton = 6.48` (DAC codes per newton of force command).

use std::fmt;
use std::path::PathBuf;

use sandjumper_core::reset::ResetCause;
use sandjumper_core::{Command, DriveCalibration};
use sandjumper_output::Progress;

pub use super::drive_calibration::{read_calibration, send_calibration};
use super::target::Target;
use crate::error::RigError;
use crate::hil::rig_model::RigModelConfig;
use crate::protocol::query_status;

/// `rig calibrate-drive`: the codes to send (and save).
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrateRequest {
    /// The controller.
    pub target: Target,
    /// DAC code at which the drive's force input reads 0 V (nominal 2048).
    pub zero_code: u16,
    /// DAC codes per newton of force command (nominal 2047 / 300 N = 6.823).
    pub codes_per_newton: f32,
    /// Save the codes in this file (TOML) for later programs' drive calibration.
    pub save: Option<PathBuf>,
}

impl CalibrateRequest {
    /// The calibration asked for.
    pub fn calibration(&self) -> DriveCalibration {
        DriveCalibration {
            zero_code: self.zero_code,
            codes_per_newton: self.codes_per_newton,
        }
    }

    /// The core's own check of the codes.
    pub fn validate(&self) -> Result<(), RigError> {
        self.calibration()
            .validate()
            .map_err(|e| RigError::input(format!("--zero-code/--codes-per-newton: {e}")))
    }
}

/// What [`calibrate`] returns: the link's name and the calibration the controller reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibrated {
    /// The link's name.
    pub link: String,
    /// The calibration the controller reports.
    pub calibration: DriveCalibration,
}

impl fmt::Display for Calibrated {
    /// The line `rig calibrate-drive` prints (with its newline).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = self.calibration;
        writeln!(
            f,
            "drive calibration on {}: zero code {}, {} codes/N (0 N -> code {}, +300 N -> {}, -300 N -> {})",
            self.link,
            c.zero_code,
            c.codes_per_newton,
            c.force_to_code(0.0),
            c.force_to_code(300.0),
            c.force_to_code(-300.0)
        )
    }
}

/// Run `rig calibrate-drive`: send the codes, read them back, save them if asked.
pub fn calibrate(
    request: &CalibrateRequest,
    _progress: &dyn Progress,
) -> Result<Calibrated, RigError> {
    request.validate()?;
    let cal = request.calibration();
    let mut link = request.target.open(&RigModelConfig::default())?;
    let name = link.name();
    send_calibration(link.as_mut(), cal)?;
    let status =
        query_status(link.as_mut()).map_err(|e| RigError::link(&name, "status query", e))?;
    link.finish()
        .map_err(|e| RigError::link(&name, "closing the session", e))?;
    if let Some(path) = &request.save {
        let text = toml::to_string(&cal)
            .map_err(|e| RigError::internal(format!("cannot encode the calibration: {e}")))?;
        std::fs::write(path, text)
            .map_err(|e| RigError::input(format!("cannot write `{}`: {e}", path.display())))?;
    }
    Ok(Calibrated {
        link: name,
        calibration: status.drive_calibration,
    })
}

/// What [`acknowledge_reset`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct Acknowledged {
    /// The link's name.
    pub link: String,
    /// The reset that was acknowledged.
    pub reset_cause: ResetCause,
}

impl fmt::Display for Acknowledged {
    /// The line `rig acknowledge-reset` prints (with its newline).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "reset ({:?}) acknowledged on {}: Arm is allowed",
            self.reset_cause, self.link
        )
    }
}

/// Run `rig acknowledge-reset`: after a reset other than power-on the board refuses `Arm`
/// until the carriage's position has been checked and this is sent.
pub fn acknowledge_reset(
    target: &Target,
    _progress: &dyn Progress,
) -> Result<Acknowledged, RigError> {
    let mut link = target.open(&RigModelConfig::default())?;
    let name = link.name();
    let before =
        query_status(link.as_mut()).map_err(|e| RigError::link(&name, "status query", e))?;
    link.command(&Command::AcknowledgeReset)
        .map_err(|e| RigError::link(&name, "acknowledging the reset", e))?;
    link.finish()
        .map_err(|e| RigError::link(&name, "closing the session", e))?;
    Ok(Acknowledged {
        link: name,
        reset_cause: before.reset_cause,
    })
}
