//! The subcommands `sandjumper fit`.
//!
//! The library items are re-exported from `sandjumper_study::fit`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_study::fit::*;

pub mod command;
