//! Why a configuration value was refused, and the check that names it: shared by the rig's
//! and a jump's configuration and by the controller's gains.

use core::fmt;

use crate::trajectory::TrajectoryError;

/// A configuration value out of range.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// `what` = `value` is not allowed; `allowed` says what is.
    Field {
        what: &'static str,
        value: f32,
        allowed: &'static str,
    },
    /// The trajectory's parameters.
    Trajectory(TrajectoryError),
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Field {
                what,
                value,
                allowed,
            } => {
                write!(f, "{what} = {value} not allowed: {allowed}")
            }
            Self::Trajectory(e) => write!(f, "trajectory: {e}"),
        }
    }
}

impl core::error::Error for ConfigError {}

impl From<TrajectoryError> for ConfigError {
    fn from(e: TrajectoryError) -> Self {
        Self::Trajectory(e)
    }
}

/// `Ok` if `ok`, else a [`ConfigError::Field`] naming the value and what is allowed.
pub(crate) fn field(
    what: &'static str,
    value: f32,
    ok: bool,
    allowed: &'static str,
) -> Result<(), ConfigError> {
    if ok {
        Ok(())
    } else {
        Err(ConfigError::Field {
            what,
            value,
            allowed,
        })
    }
}
