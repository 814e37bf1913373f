//! The subcommands `sandjumper figures`.
//!
//! The library items are re-exported from `sandjumper_study::figures`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_study::figures::*;

pub mod command;
