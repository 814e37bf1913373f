//! The subcommands `sandjumper sweep` (on this machine or, with `--slurm`, as a Slurm job
//! array) and `merge`.
//!
//! The library items are re-exported from `sandjumper_study::sweep`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_study::sweep::*;

pub mod command;
pub mod merge_command;
pub mod slurm;
