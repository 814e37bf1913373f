//! The subcommands `sandjumper dem`: beds, intrusions, collision checks.
//!
//! The library items are re-exported from `sandjumper_dem`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_dem::*;

pub mod command;
pub mod lammps_command;
pub mod paper_figures;
