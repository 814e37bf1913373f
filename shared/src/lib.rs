//! `sandjumper-core`: the `no_std` core shared by the firmware and the host.
//!
//! Sans-IO: nothing here knows a register, a file, a thread or a clock. Inputs arrive as
//! values, outputs leave as values.
#![no_std]

pub mod trajectory;

pub use trajectory::{JumpKind, Kinematics, SineJump, TrajectoryError};
