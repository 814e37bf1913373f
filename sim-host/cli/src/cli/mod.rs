//! The `sandjumper` command line: parse, dispatch to the subcommand, map errors to the exit status.
//!
//! [`run`] parses the arguments (clap), runs the command and returns the exit status:
//! 0 success; **2 bad input** (usage errors, bad values, unreadable or ill-typed parameter
//! files, an output directory that cannot be written, shards that do not merge, and every
//! error the simulator reports); 1 an internal failure after the input was accepted (a file
//! that could not be written half-way, a figure that could not be drawn). Every error is one
//! message on stderr saying what was wrong, where, and what is allowed; nothing is left
//! half-written as if complete (see [`sandjumper_output::StagedDir`]).
//!
//! Each subcommand's arguments and code live in the room of what it does (`study/`, `rig/`);
//! this module only parses and dispatches. What every subcommand shares (the error type,
//! argument vocabulary, progress bars) is in [`crate::command`].

pub mod args;
mod params_command;

use std::ffi::OsString;
use std::process::ExitCode;

use clap::Parser;

pub use crate::command::{CliError, EXIT_BAD_INPUT, EXIT_INTERNAL};
pub use args::Cli;

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
        args::Command::Jump(a) => crate::study::jump_command::run(&a),
        args::Command::Sweep(a) => crate::study::sweep::run(&a),
        args::Command::Merge(a) => crate::study::sweep::run_merge(&a),
        args::Command::Params(a) => params_command::run(&a),
        args::Command::Fit(a) => crate::study::fit::run(&a),
        args::Command::Figures(a) => crate::study::figures::run(&a),
        args::Command::Optimize(a) => crate::optimize::command::run(&a),
        args::Command::Hil(a) => crate::rig::hil::command::run(&a),
        args::Command::Replay(a) => crate::study::replay::run(&a),
        args::Command::Log(a) => crate::acqlog::command::run(&a),
        args::Command::Track(a) => crate::imaging::command::run(&a),
        args::Command::CameraScale(a) => crate::imaging::command::run_scale(&a),
        args::Command::Piv(a) => crate::flow::command::run(&a),
        args::Command::PivSynthetic(a) => crate::flow::command::run_synthetic(&a),
        args::Command::Rig(a) => crate::rig::tool::run(&a),
        args::Command::Dem(a) => crate::dem::command::run(&a),
        args::Command::Campaign(a) => crate::campaign::command::run(&a),
    }
}
