//! The subcommands `sandjumper replay`.
//!
//! The library items are re-exported from `sandjumper_study::replay`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_study::replay::*;

pub mod command;
