//! The subcommands `sandjumper jump`, `sweep`, `merge`, `replay`, `fit`, `figures`: faces over
//! `sandjumper_study`'s calls.
//!
//! The library items are re-exported from `sandjumper_study`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_study::*;

pub mod figures;
pub mod fit;
pub mod jump_command;
pub mod replay;
pub mod sweep;

pub use crate::command::progress::cli_error;
