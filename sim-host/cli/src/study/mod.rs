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

/// Write a jump's folder (when `staged`, with `write`) and say so on stderr, then print the
/// outcome: its `json` with `--json`, else its human summary (`jump` and `replay`).
fn print_jump(
    staged: Option<sandjumper_output::StagedDir>,
    write: impl FnOnce(&sandjumper_output::StagedDir) -> Result<(), StudyError>,
    json: bool,
    text: &str,
    human: &impl std::fmt::Display,
) -> Result<(), crate::command::CliError> {
    if let Some(staged) = staged {
        write(&staged)?;
        let dir = staged.commit()?;
        eprintln!(
            "wrote {}/ (trajectory.csv, params.toml, summary.json, jump.png, jump.svg)",
            dir.display()
        );
    }
    if json {
        println!("{text}");
    } else {
        print!("{human}");
    }
    Ok(())
}

/// Each of `warnings` on stderr as `warning: ...`.
fn warn(warnings: &[String]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}
