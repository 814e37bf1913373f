//! The subcommands `sandjumper jump`, `sweep`, `merge`, `replay`, `fit`, `figures`: faces over
//! `sandjumper_study`'s calls.
//!
//! The library items are re-exported from `sandjumper_study`, so a subcommand reads them as its
//! neighbours.

pub use sandjumper_study::*;

use sandjumper_output::{Blame, Blamed, CliError, EXIT_BAD_INPUT, EXIT_INTERNAL};

pub mod figures;
pub mod fit;
pub mod jump_command;
pub mod replay;
pub mod sweep;

/// A library error as the command line reports it: its message, exit status 2 when it is the
/// caller's input, 1 otherwise.
pub fn cli_error<E: Blamed>(e: E) -> CliError {
    CliError {
        message: e.to_string(),
        exit: match e.blame() {
            Blame::Input => EXIT_BAD_INPUT,
            Blame::Internal => EXIT_INTERNAL,
        },
    }
}
