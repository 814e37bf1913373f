//! The drive calibration file (TOML: `zero_code = 2101`, the DAC code at which the drive
//! reads 0 V; `codes_per_newton = 6.48`, DAC codes per newton of force command) read and
//! checked, and sent to the controller: what `rig calibrate-drive` saves and every program
//! given a [`super::target::Target::drive_calibration`] sends when its session opens.

use std::path::Path;

use sandjumper_core::{Command, DriveCalibration};

use crate::error::RigError;
use crate::protocol::link::RigLink;

/// Read and check a calibration file: the file, the key and what is allowed on error.
pub fn read_calibration(path: &Path) -> Result<DriveCalibration, RigError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        RigError::input(format!(
            "cannot read the drive calibration `{}`: {e}",
            path.display()
        ))
    })?;
    parse_calibration(&text)
        .map_err(|e| RigError::input(format!("drive calibration `{}`: {e}", path.display())))
}

/// [`read_calibration`] of a file's text: a calibration the controller accepts, or why not
/// (without the file's name).
pub fn parse_calibration(text: &str) -> Result<DriveCalibration, String> {
    let cal: DriveCalibration = toml::from_str(text)
        .map_err(|e| format!("{e} (allowed: zero_code = CODE, codes_per_newton = X)"))?;
    cal.validate().map_err(|e| e.to_string())?;
    Ok(cal)
}

/// Send `cal` to the controller (it refuses while the drive is enabled).
pub fn send_calibration(link: &mut dyn RigLink, cal: DriveCalibration) -> Result<(), RigError> {
    let name = link.name();
    link.command(&Command::SetDriveCalibration(cal))
        .map_err(|e| RigError::link(&name, "setting the drive calibration", e))?;
    Ok(())
}
