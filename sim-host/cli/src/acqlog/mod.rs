//! The subcommands `sandjumper log`: check or convert acquisition logs.
//!
//! The library items are re-exported from `sandjumper_acqlog`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_acqlog::*;

pub mod command;
