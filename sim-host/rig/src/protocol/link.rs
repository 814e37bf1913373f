//! One interface to the controller, three ways to reach it: [`RigLink`].
//!
//! Every link exchanges the core protocol's lockstep frames (`sandjumper_core::protocol`): one
//! [`SensorFrame`] in, one [`ActuatorFrame`] out per control period, and the protocol's
//! [`Command`]s to configure, arm and start the jump.
//!
//! | link | the controller | transport |
//! |---|---|---|
//! | [`crate::hil::sil::SilLink`] | the core's [`sandjumper_core::Rig`] in this process | values (corrupted frames go through the real decoder) |
//! | [`crate::hil::framed::FramedLink`] via [`crate::hil::pil`] | the real firmware in QEMU `mps2-an386` | COBS frames over semihosting FIFOs (`-icount`) or the CMSDK UART |
//! | [`crate::hil::framed::FramedLink`] via [`crate::hil::serial`] | the F407 firmware in its HIL mode | COBS frames over USB CDC |

use sandjumper_core::protocol::{FaultReport, encode_frame_vec};
use sandjumper_core::rig::Counters;
use sandjumper_core::{
    ActuatorFrame, Command, HostMessage, Rejection, Reply, SampleRecord, SensorFrame, Status,
};
use std::fmt;

/// Why a link failed.
#[derive(Clone, Debug, PartialEq)]
pub enum LinkError {
    /// The controller refused a command (what it was, why).
    Rejected { command: String, why: Rejection },
    /// The controller did not answer in time (what was awaited, seconds waited).
    Timeout { waiting_for: String, seconds: f64 },
    /// The link closed while an answer was awaited.
    Closed { waiting_for: String },
    /// Starting or talking to the transport failed (what, the OS or tool's message).
    Io { what: String, message: String },
    /// The controller answered something out of protocol.
    Protocol(String),
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Rejected { command, why } => {
                write!(f, "the controller rejected {command}: {why}")
            }
            Self::Timeout {
                waiting_for,
                seconds,
            } => {
                write!(
                    f,
                    "no answer to {waiting_for} within {seconds} s (controller hung?)"
                )
            }
            Self::Closed { waiting_for } => {
                write!(f, "the link closed while waiting for {waiting_for}")
            }
            Self::Io { what, message } => write!(f, "{what}: {message}"),
            Self::Protocol(m) => write!(f, "protocol violation: {m}"),
        }
    }
}

impl std::error::Error for LinkError {}

/// What a link reports when it is closed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinkReport {
    /// The controller's last status (its counters), if it sent one.
    pub final_status: Option<Status>,
    /// The most instructions one control tick took (PIL: measured with QEMU `-icount`).
    pub max_tick_instructions: Option<u32>,
    /// The controller process's exit status (PIL), if it has one.
    pub exit_code: Option<i32>,
    /// Frames from the controller the host could not decode (bad CRC, malformed, ...).
    pub host_frames_rejected: u32,
    /// The jump height of the plant a virtual board moved (`--link f407`), m.
    pub simulated_jump_height_m: Option<f64>,
    /// Virtual over wall time of a virtual board's run (`--link f407`), start-up included.
    pub board_realtime_factor: Option<f64>,
}

impl LinkReport {
    /// The controller's counters from its final status, if any.
    pub fn counters(&self) -> Option<Counters> {
        self.final_status.map(|s| s.counters)
    }
}

/// A way to reach the controller.
pub trait RigLink {
    /// Short name (`sil`, `pil`, `pil-uart`, `serial:/dev/ttyACM0`).
    fn name(&self) -> String;

    /// Send a command and wait for its reply.
    fn command(&mut self, command: &Command) -> Result<Reply, LinkError>;

    /// One lockstep period: send `frame`, wait for the actuator frame answering it.
    fn exchange(&mut self, frame: &SensorFrame) -> Result<ActuatorFrame, LinkError>;

    /// Send `frame` with one bit flipped on the wire (fault injection). The controller must
    /// reject and count it; no answer is awaited (the drive holds its last command).
    fn send_corrupted(&mut self, frame: &SensorFrame) -> Result<(), LinkError>;

    /// One period passes with no sensor frame sent (fault injection: the link stops). Returns
    /// the controller's output if it produced one on its own (a link-lost fault).
    fn silent_period(&mut self) -> Result<Option<ActuatorFrame>, LinkError>;

    /// Sample records received since the last call, in sequence order.
    fn take_samples(&mut self) -> Vec<SampleRecord>;

    /// Fault reports received since the last call.
    fn take_faults(&mut self) -> Vec<FaultReport>;

    /// End the session: close the link, collect the remaining telemetry and the final status.
    fn finish(&mut self) -> Result<LinkReport, LinkError>;
}

/// The wire bytes of a sensor frame with one bit flipped inside the COBS body (the CRC no
/// longer matches; the delimiter is kept so the receiver resynchronises on it).
pub fn corrupted_sensor_frame(frame: &SensorFrame) -> Vec<u8> {
    let mut bytes = encode_frame_vec(&HostMessage::Sensor(*frame))
        .map(|v| v.to_vec())
        .unwrap_or_default();
    if bytes.len() > 2 {
        let i = bytes.len() / 2;
        // Flip a bit but never create a 0x00 (that would split the frame in two).
        bytes[i] = if bytes[i] ^ 0x10 == 0 {
            bytes[i] ^ 0x20
        } else {
            bytes[i] ^ 0x10
        };
    }
    bytes
}

/// `Reply` or a [`LinkError::Rejected`] naming the command.
pub fn reply_or_rejected(
    command: &Command,
    result: Result<Reply, Rejection>,
) -> Result<Reply, LinkError> {
    result.map_err(|why| LinkError::Rejected {
        command: format!("{:?}", command.kind()),
        why,
    })
}
