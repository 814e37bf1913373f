//! The subcommands `sandjumper piv` and `piv-synthetic`.
//!
//! The library items are re-exported from `sandjumper_flow`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_flow::*;

pub mod command;
