//! The subcommands `sandjumper track` and `camera-scale`: the rod camera's frames.
//!
//! The library items are re-exported from `sandjumper_imaging`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_imaging::*;

pub mod command;
