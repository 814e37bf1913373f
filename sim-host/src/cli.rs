//! The `sandjumper` command line: `jump`, `sweep`, `merge`, `params`.
//!
//! [`run`] parses the arguments (clap), runs the command and returns the exit status:
//! 0 success; **2 bad input** (usage errors, bad values, unreadable or ill-typed parameter
//! files, an output directory that cannot be written, shards that do not merge, and every
//! error the simulator reports); 1 an internal failure after the input was accepted (a file
//! that could not be written half-way, a figure that could not be drawn). Every error is one
//! message on stderr saying what was wrong, where, and what is allowed; nothing is left
//! half-written as if complete (see [`crate::output::StagedDir`]).
//!
//! The modules hold the pieces other commands reuse: [`args`] (clap definitions and value
//! parsers), [`resolve`] (parameters from `--phi` and `--params`).

pub mod args;
pub(crate) mod jump_cmd;
mod merge_cmd;
mod params_cmd;
pub mod resolve;
mod sweep_cmd;

use std::ffi::OsString;
use std::fmt;
use std::process::ExitCode;

use clap::Parser;

pub use args::Cli;

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

impl From<crate::output::OutputError> for CliError {
    fn from(e: crate::output::OutputError) -> Self {
        Self::input(e.to_string())
    }
}

impl From<crate::plot::PlotError> for CliError {
    fn from(e: crate::plot::PlotError) -> Self {
        Self::internal(e.to_string())
    }
}

/// Parse `args` (including the program name), run the command, return the exit status.
pub fn run<I, T>(args: I) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout with status 0; usage errors to stderr with 2.
            let _ = e.print();
            return ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(EXIT_BAD_INPUT));
        }
    };
    match execute(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", e.message);
            ExitCode::from(e.exit)
        }
    }
}

/// Run a parsed command.
pub fn execute(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        args::Command::Jump(a) => jump_cmd::run(&a),
        args::Command::Sweep(a) => sweep_cmd::run(&a),
        args::Command::Merge(a) => merge_cmd::run(&a),
        args::Command::Params(a) => params_cmd::run(&a),
        args::Command::Fit(a) => crate::fit::command::run(&a),
        args::Command::Figures(a) => crate::figures::command::run(&a),
        args::Command::Hil(a) => crate::hil::command::run(&a),
        args::Command::Replay(a) => crate::replay_cmd::run(&a),
        args::Command::Log(a) => crate::acqlog::command::run(&a),
        args::Command::Rig(a) => crate::rig_tool::run(&a),
    }
}
