//! What the rig reports of itself: its state machine's states and the `Status` snapshot with
//! its counters (nothing is lost silently). Shared by the rig, its commands and the protocol.

use crate::drive_calibration::DriveCalibration;
use crate::fault::FaultCode;
use crate::profile::Phase;
use crate::reset::ResetCause;

/// Where the rig is in its state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RigState {
    /// Drive disabled, zero force.
    Idle,
    /// Drive enabled, holding the trajectory's start position.
    Armed,
    /// Running the trajectory (see [`Phase`]).
    Running,
    /// Trajectory over, holding its final position; camera still running.
    Done,
    /// A fault is latched: drive disabled, zero force until `ClearFault`.
    Faulted,
}

impl RigState {
    /// The drive is enabled in this state.
    pub fn drive_enabled(self) -> bool {
        matches!(self, Self::Armed | Self::Running | Self::Done)
    }
}

/// Counters reported in telemetry: nothing is lost silently.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Sample records produced (= next sequence number).
    pub samples_produced: u32,
    /// Sample records dropped because the queue was full.
    pub samples_dropped: u32,
    /// Frames received and decoded.
    pub frames_ok: u32,
    /// Frames rejected (malformed, truncated, bad CRC, wrong version).
    pub frames_rejected: u32,
    /// Lockstep sensor frames missing (gaps in the frame counter).
    pub lockstep_frames_lost: u32,
    /// Commands rejected.
    pub commands_rejected: u32,
    /// Faults detected while another was already latched.
    pub faults_after_latch: u32,
    /// Longest tick reported by the glue, cycles.
    pub max_tick_cycles: u32,
    /// Control ticks that never ran (a gap between two tick starts of more than one and a
    /// half periods: an interrupt missed or merged), as reported by the glue.
    pub ticks_missed: u32,
    /// Frames from the host the glue could not queue for the core (its inbound queue was
    /// full), as reported by the glue.
    pub frames_dropped: u32,
}

/// A snapshot of the rig for the host.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// State machine.
    pub state: RigState,
    /// Trajectory phase.
    pub phase: Phase,
    /// Latched fault.
    pub fault: Option<FaultCode>,
    /// Tick the fault was latched on.
    pub fault_tick: u32,
    /// Ticks since start-up.
    pub tick: u32,
    /// Ticks since the trajectory started.
    pub run_tick: u32,
    /// Camera frames triggered in this run.
    pub camera_frames: u32,
    /// A jump configuration is loaded.
    pub configured: bool,
    /// Checksum of the committed replay table.
    pub replay_checksum: Option<u32>,
    /// Counters.
    pub counters: Counters,
    /// Why the board last reset.
    pub reset_cause: ResetCause,
    /// `Arm` is allowed: a power-on reset, or a later reset acknowledged by the host.
    pub reset_acknowledged: bool,
    /// The DAC codes of the force command in use.
    pub drive_calibration: DriveCalibration,
    /// The bed apparatus.
    pub bed: crate::bed::BedStatus,
    /// The board's own emergency-stop loop.
    pub emergency_stop: crate::emergency_stop::EmergencyStopStatus,
}

impl Status {
    /// A stop is pressed now: the board's loop reads open, or the bed apparatus reports its
    /// stop (or its harness lost).
    pub fn emergency_stop_pressed(&self) -> bool {
        self.emergency_stop.open || (self.bed.present && self.bed.inputs.emergency_stop)
    }
}
