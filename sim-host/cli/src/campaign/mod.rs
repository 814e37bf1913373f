//! The subcommands `sandjumper campaign`: run, resume, status.
//!
//! The library items are re-exported from `sandjumper_campaign`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_campaign::*;

pub mod command;
