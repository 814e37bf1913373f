//! The rig tool (`sandjumper rig`): one typed call per command, all through the one session
//! every program runs ([`session::run_program`]) on any link ([`target::Target`]).
//!
//! - [`status`]: the controller's state, fault and counters (once, or watched).
//! - [`jump`]: configure, arm and run one sine jump; its acquisition log and a figure.
//! - [`intrude`]: the slow-intrusion program; the force-vs-depth curves.
//! - [`replay`]: upload an (edited) encoder record or a stroke table, verify it, run it.
//! - [`calibrate`]: send (and save) the drive's DAC calibration; acknowledge a reset;
//!   [`drive_calibration`]: its file, read and sent.
//! - [`flash`]: write the F407 firmware with the probe-rs CLI (an external program).
//!
//! What a program leaves behind is [`output`]; the clamped slow-intrusion rig is
//! [`intrusion_fixture`].

pub mod calibrate;
pub mod drive_calibration;
pub mod flash;
pub mod intrude;
pub mod intrusion_fixture;
pub mod jump;
pub mod output;
pub mod replay;
pub mod session;
pub mod status;
pub mod target;
pub mod watched;
