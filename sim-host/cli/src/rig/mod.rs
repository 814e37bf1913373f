//! The subcommands `sandjumper hil` and `sandjumper rig`.
//!
//! The library items are re-exported from `sandjumper_rig`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_rig::*;

pub mod hil;
pub mod tool;
