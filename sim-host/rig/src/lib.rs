//! The rig and its stand-ins: the control loop closed through a link ([`hil`]: the core
//! in-process, the real firmware under QEMU, or a board on a serial port), the host tool
//! for a board ([`tool`]), and which board a firmware image was built for ([`firmware_image`]).
//! Both write acquisition logs ([`sandjumper_acqlog`]).

pub mod firmware_image;
pub mod hil;
pub mod stroke_table;
pub mod tool;
