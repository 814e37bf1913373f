//! The rig and its stand-ins: the control loop closed through a link ([`hil`]: the core
//! in-process, the real firmware under QEMU, or a board on a serial port), the host tool
//! for a board ([`tool`]), and which board a firmware image was built for ([`firmware_image`]).
//! Both write acquisition logs ([`sandjumper_acqlog`]) and stand on [`protocol`] (the link
//! and the controller's status).
//!
//! Every command is one typed call: [`hil_command::run`] (`sandjumper hil`, every link) and
//! the rig tool's [`tool::status`], [`tool::jump`], [`tool::intrude`], [`tool::replay`],
//! [`tool::calibrate`] and [`tool::flash`]. Errors are [`RigError`]; a run shows its steps to a
//! [`watch::RunWatch`]; [`live::RigLiveView`] is the one that shows it on a live view.

pub mod error;
pub mod firmware_image;
pub mod hil;
pub mod hil_command;
pub mod live;
pub mod protocol;
pub mod stroke_table;
pub mod tool;
pub mod watch;

pub use error::RigError;
