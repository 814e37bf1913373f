//! Host commands to the rig, the rig's replies, and why a command can be rejected.

use crate::bed::{BedCommand, BedError};
use crate::drive_calibration::{CalibrationError, DriveCalibration};
use crate::emergency_stop::EmergencyStopError;
use crate::reset::ResetCause;
use core::fmt;

use crate::config::{ConfigError, JumpConfig};
use crate::controller::Gains;
use crate::replay::ReplayError;
use crate::status::{RigState, Status};

/// Samples per `ReplayChunk` command (fits a frame with room to spare).
pub const REPLAY_CHUNK: usize = 64;

/// A command from the host.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Load a jump configuration (Idle or Done; the rig goes to Idle). An invalid one is
    /// rejected and latches `InvalidConfiguration`.
    Configure(JumpConfig),
    /// Idle -> Armed: drive enabled, holding the trajectory's start position.
    Arm,
    /// Armed -> Running: the trajectory and the camera start on the next tick.
    Start,
    /// Armed/Running/Done -> Idle: zero force, drive disabled (a no-op in Idle).
    Abort,
    /// Faulted -> Idle.
    ClearFault,
    /// Start a replay upload of `len` samples, one every `period_ticks` ticks.
    ReplayBegin { len: u32, period_ticks: u32 },
    /// Samples `offset..offset+samples.len()` of the upload, m (in order).
    ReplayChunk {
        offset: u32,
        samples: heapless::Vec<f32, REPLAY_CHUNK>,
    },
    /// Finish the upload; `checksum` is [`crate::replay::replay_checksum`] of all samples.
    ReplayCommit { checksum: u32 },
    /// Replace the gains of the loaded jump (not while Running).
    SetGains(Gains),
    /// Ask for a [`Status`].
    StatusQuery,
    /// Keep the host-link watchdog fed; no other effect.
    Heartbeat,
    /// The carriage's position after a reset other than power-on has been checked (homed, or
    /// seen by hand): `Arm` is allowed again.
    AcknowledgeReset,
    /// The DAC codes of the force command measured on the rig (drive disabled: Idle or
    /// Faulted only). Checked, then used for every force command and reported in `Status`.
    SetDriveCalibration(DriveCalibration),
    /// A bed-apparatus command (blower, shaker, lift), in any state, under the interlocks of
    /// [`crate::bed`].
    Bed(BedCommand),
}

/// Which command (for rejections).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CommandKind {
    Configure,
    Arm,
    Start,
    Abort,
    ClearFault,
    ReplayBegin,
    ReplayChunk,
    ReplayCommit,
    SetGains,
    StatusQuery,
    Heartbeat,
    AcknowledgeReset,
    SetDriveCalibration,
    Bed,
}

impl Command {
    /// Which command this is.
    pub fn kind(&self) -> CommandKind {
        match self {
            Self::Configure(_) => CommandKind::Configure,
            Self::Arm => CommandKind::Arm,
            Self::Start => CommandKind::Start,
            Self::Abort => CommandKind::Abort,
            Self::ClearFault => CommandKind::ClearFault,
            Self::ReplayBegin { .. } => CommandKind::ReplayBegin,
            Self::ReplayChunk { .. } => CommandKind::ReplayChunk,
            Self::ReplayCommit { .. } => CommandKind::ReplayCommit,
            Self::SetGains(_) => CommandKind::SetGains,
            Self::StatusQuery => CommandKind::StatusQuery,
            Self::Heartbeat => CommandKind::Heartbeat,
            Self::AcknowledgeReset => CommandKind::AcknowledgeReset,
            Self::SetDriveCalibration(_) => CommandKind::SetDriveCalibration,
            Self::Bed(_) => CommandKind::Bed,
        }
    }
}

/// A successful command's reply.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reply {
    /// Done.
    Ack,
    /// The answer to `StatusQuery`.
    Status(Status),
}

/// Why a command was refused. A refused command changes nothing, except that an invalid
/// configuration also latches the `InvalidConfiguration` fault.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CommandError {
    /// The command is not legal in this state.
    IllegalInState {
        command: CommandKind,
        state: RigState,
    },
    /// Arm or SetGains without a loaded configuration.
    NotConfigured,
    /// The configuration failed validation.
    InvalidConfiguration(ConfigError),
    /// A replay upload step failed.
    Replay(ReplayError),
    /// `Arm` after a reset other than power-on, not yet acknowledged (`AcknowledgeReset`).
    ResetNotAcknowledged { cause: ResetCause },
    /// The drive calibration failed its check.
    InvalidCalibration(CalibrationError),
    /// A bed interlock refused the command (or `Arm`).
    Interlock(BedError),
    /// The board's emergency-stop loop refused `Arm` (or a bed command that switches
    /// something on).
    EmergencyStop(EmergencyStopError),
}

impl fmt::Display for CommandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::IllegalInState { command, state } => {
                write!(f, "{command:?} is not allowed in state {state:?}")
            }
            Self::NotConfigured => write!(f, "no jump configured (send Configure first)"),
            Self::InvalidConfiguration(e) => write!(f, "invalid configuration: {e}"),
            Self::Replay(e) => write!(f, "replay upload: {e}"),
            Self::ResetNotAcknowledged { cause } => write!(
                f,
                "the board reset ({cause:?}) since power-on: position zero may have moved; home \
                 or check the carriage, then send AcknowledgeReset"
            ),
            Self::InvalidCalibration(e) => write!(f, "drive calibration refused: {e}"),
            Self::Interlock(e) => write!(f, "bed interlock: {e}"),
            Self::EmergencyStop(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for CommandError {}

/// The wire form of a [`CommandError`] (no borrowed text).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// See [`CommandError::IllegalInState`].
    IllegalInState {
        command: CommandKind,
        state: RigState,
    },
    /// See [`CommandError::NotConfigured`].
    NotConfigured,
    /// See [`CommandError::InvalidConfiguration`]; the fault is latched.
    InvalidConfiguration,
    /// Replay upload failed; for a checksum mismatch `actual` is the table's checksum.
    Replay { actual_checksum: Option<u32> },
    /// See [`CommandError::ResetNotAcknowledged`].
    ResetNotAcknowledged { cause: ResetCause },
    /// See [`CommandError::InvalidCalibration`].
    InvalidCalibration(CalibrationError),
    /// See [`CommandError::Interlock`].
    Interlock(BedError),
    /// See [`CommandError::EmergencyStop`].
    EmergencyStop(EmergencyStopError),
}

impl fmt::Display for Rejection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::IllegalInState { command, state } => {
                write!(f, "{command:?} is not allowed in state {state:?}")
            }
            Self::NotConfigured => write!(f, "no jump configured (send Configure first)"),
            Self::InvalidConfiguration => write!(
                f,
                "invalid configuration (the InvalidConfiguration fault is latched)"
            ),
            Self::Replay {
                actual_checksum: Some(c),
            } => write!(
                f,
                "replay upload: checksum mismatch (the table's is {c:#010x})"
            ),
            Self::Replay {
                actual_checksum: None,
            } => write!(f, "replay upload refused"),
            Self::ResetNotAcknowledged { cause } => {
                write!(f, "{}", CommandError::ResetNotAcknowledged { cause })
            }
            Self::InvalidCalibration(e) => write!(f, "drive calibration refused: {e}"),
            Self::Interlock(e) => write!(f, "bed interlock: {e}"),
            Self::EmergencyStop(e) => write!(f, "{e}"),
        }
    }
}

impl From<&CommandError> for Rejection {
    fn from(e: &CommandError) -> Self {
        match *e {
            CommandError::IllegalInState { command, state } => {
                Self::IllegalInState { command, state }
            }
            CommandError::NotConfigured => Self::NotConfigured,
            CommandError::InvalidConfiguration(_) => Self::InvalidConfiguration,
            CommandError::Replay(ReplayError::Checksum { actual, .. }) => Self::Replay {
                actual_checksum: Some(actual),
            },
            CommandError::Replay(_) => Self::Replay {
                actual_checksum: None,
            },
            CommandError::ResetNotAcknowledged { cause } => Self::ResetNotAcknowledged { cause },
            CommandError::InvalidCalibration(e) => Self::InvalidCalibration(e),
            CommandError::Interlock(e) => Self::Interlock(e),
            CommandError::EmergencyStop(e) => Self::EmergencyStop(e),
        }
    }
}

/// The commands that upload `samples` (m, one every `period_ticks` control ticks) to the rig's
/// replay table: `ReplayBegin`, the chunks in order, `ReplayCommit` with the table's checksum.
/// Follow with `Configure` of `TrajectorySpec::Replay { checksum: replay_checksum(samples) }`.
pub fn replay_upload(samples: &[f32], period_ticks: u32) -> impl Iterator<Item = Command> + '_ {
    let begin = Command::ReplayBegin {
        len: samples.len() as u32,
        period_ticks,
    };
    let chunks = samples
        .chunks(REPLAY_CHUNK)
        .enumerate()
        .map(|(k, c)| Command::ReplayChunk {
            offset: (k * REPLAY_CHUNK) as u32,
            // `chunks(REPLAY_CHUNK)` never yields more than the capacity.
            samples: heapless::Vec::from_slice(c).unwrap_or_default(),
        });
    let commit = Command::ReplayCommit {
        checksum: crate::replay::replay_checksum(samples),
    };
    core::iter::once(begin)
        .chain(chunks)
        .chain(core::iter::once(commit))
}
