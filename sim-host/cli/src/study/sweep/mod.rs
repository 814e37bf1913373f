//! The subcommands `sandjumper sweep` and `merge`.
//!
//! The library items are re-exported from `sandjumper_study::sweep`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_study::sweep::*;

pub mod command;
pub mod merge_command;
