//! Hardware in the loop: the simulator stands in for the STA-1104 rig (motor, rod, spring,
//! foot and sand) and the controller cannot tell the difference.
//!
//! - [`rig_model`]: the force-driven plant behind a DAC-quantized drive, a quantized encoder
//!   and a camera (docs/model.md sections 1 and 6).
//! - [`link`]: [`RigLink`], the one interface to the controller; [`sil`] (the core in this
//!   process), [`framed`] (the wire protocol over a byte stream) used by [`pil`] (the real
//!   firmware in QEMU) and [`serial`] (a real F407 over USB CDC); [`virtual_board`] (the F407
//!   release binary on the virtual board, `--link f407`).
//! - [`run`]: one jump through the loop; [`log`]: its acquisition log and figure;
//!   [`open`]: which link and opening it (`sandjumper hil` lives in the CLI crate);
//!   [`loop_margins`]: the position loop's stability margins
//!   on the rig, from its linear model.

pub mod affinity;
pub mod camera;
pub mod emulated_firmware;
pub mod framed;
pub mod log;
pub mod loop_margins;
pub mod open;
pub mod pil;
pub mod rig_model;
pub mod run;
pub mod serial;
pub mod sil;
pub mod virtual_board;

/// The link layer lives in [`crate::protocol`], under both the loop runs and the rig tool.
pub use crate::protocol::link;

pub use link::{LinkError, LinkReport, RigLink};
pub use rig_model::{CameraFrame, DacScaling, EncoderInjection, RigModel, RigModelConfig};
pub use run::{
    HilError, HilOutcome, HilSpec, InjectedFault, Injection, PeriodView, TraceRow, run_jump,
    run_jump_observed,
};
pub use sil::SilLink;
