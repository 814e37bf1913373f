//! The subcommands `sandjumper hil` and `sandjumper rig`: faces over `sandjumper_rig`'s typed
//! calls ([`sandjumper_rig::hil_command`], [`sandjumper_rig::tool`]).
//!
//! The library items are re-exported from `sandjumper_rig`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_rig::*;

pub mod face;
pub mod hil;
pub mod tool;
