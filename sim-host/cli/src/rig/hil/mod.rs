//! The subcommands `sandjumper hil`.
//!
//! The library items are re-exported from `sandjumper_rig::hil`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_rig::hil::*;

pub mod command;
