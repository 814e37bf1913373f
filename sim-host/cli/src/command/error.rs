//! The error every command returns (one message and an exit status), and a library error as
//! the command line's ([`cli_error`]).

use std::fmt;

use sandjumper_output::{Blame, Blamed};

/// Exit status for bad input (the same as clap's usage errors).
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit status for an internal failure after the input was accepted.
pub const EXIT_INTERNAL: u8 = 1;

/// A command failed: the message to print and the exit status.
#[derive(Debug, Clone, PartialEq)]
pub struct CliError {
    /// One message: what, where, what is allowed.
    pub message: String,
    /// [`EXIT_BAD_INPUT`] or [`EXIT_INTERNAL`].
    pub exit: u8,
}

impl CliError {
    /// Bad input (exit 2).
    pub fn input(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            exit: EXIT_BAD_INPUT,
        }
    }

    /// Internal failure (exit 1).
    pub fn internal(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            exit: EXIT_INTERNAL,
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for CliError {}

/// A library error as the command line's (so `?` converts it): see [`cli_error`].
impl<E: Blamed> From<E> for CliError {
    fn from(e: E) -> Self {
        cli_error(e)
    }
}

/// A library error as the command line's: its message, exit status 2 for bad input and 1
/// for an internal failure.
pub fn cli_error<E: Blamed>(e: E) -> CliError {
    CliError {
        message: e.to_string(),
        exit: match e.blame() {
            Blame::Input => EXIT_BAD_INPUT,
            Blame::Internal => EXIT_INTERNAL,
        },
    }
}
