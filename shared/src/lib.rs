//! `sandjumper-core`: the `no_std` core shared by the firmware and the host.
//!
//! Sans-IO: nothing here knows a register, a file, a thread or a clock. Inputs arrive as
//! values ([`TickInput`], [`Command`], [`SensorFrame`]), outputs leave as values
//! ([`TickOutput`], [`Reply`], [`SampleRecord`], [`ActuatorFrame`]). The firmware's timer
//! interrupt, the QEMU lockstep loop and the simulator's software-in-the-loop all call
//! [`Rig::tick`] the same way.
//!
//! Modules, one concept each:
//! * [`trajectory`]: the exact f64 one-cycle sine jumps (docs/model.md section 2).
//! * [`intrusion`]: the slow-intrusion program; [`replay`]: the uploaded table.
//! * [`profile`]: any trajectory sampled per control tick in f32 (exact phase, 0.1 um).
//! * [`turns`]: sine/cosine of an exact fixed-point phase.
//! * [`controller`]: PD + feedforward (+I) with gain-lowering damping.
//! * [`encoder`], [`camera`], [`sample`]: acquisition.
//! * [`fault`]: the fault-code table; [`rig`]: the state machine and control loop.
//! * [`bed`]: the bed apparatus (blower, shaker, lift) and its interlocks.
//! * [`emergency_stop`]: the board's own emergency-stop loop.
//! * [`config`], [`command`], [`protocol`]: configuration, commands, wire format.
#![no_std]

#[cfg(test)]
extern crate std;

pub mod approach;
pub mod bed;
pub mod camera;
pub mod command;
pub mod config;
pub mod config_error;
pub mod controller;
pub mod drive_calibration;
pub mod emergency_stop;
pub mod encoder;
pub mod fault;
pub mod intrusion;
pub mod lockstep;
pub mod profile;
pub mod protocol;
pub mod replay;
pub mod reset;
pub mod rig;
pub mod sample;
pub mod status;
pub mod stroke;
pub mod trajectory;
pub mod turns;

pub use command::{Command, CommandError, CommandKind, Rejection, Reply};
pub use config::{ConfigError, JumpConfig, RigConfig, TrajectorySpec};
pub use controller::{GainLowering, Gains};
pub use drive_calibration::DriveCalibration;
pub use encoder::CounterWidth;
pub use fault::FaultCode;
pub use intrusion::SlowIntrusion;
pub use profile::{Phase, Setpoint};
pub use protocol::{ActuatorFrame, FrameDecoder, FrameError, HostMessage, RigMessage, SensorFrame};
pub use reset::ResetCause;
pub use rig::{Rig, TickInput, TickOutput, TickTiming};
pub use sample::SampleRecord;
pub use status::{RigState, Status};
pub use trajectory::{JumpKind, Kinematics, SineJump, TrajectoryError};
