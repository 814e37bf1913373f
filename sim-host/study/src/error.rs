//! Why a study command failed: the caller's input or the program (see [`Blamed`]).

use sandjumper_output::plot::PlotError;
use sandjumper_output::{Blame, Blamed, OutputError};

/// The error of every command-level call of this crate (`jump::run`, `sweep::run`, ...): one
/// message, as the command line prints it, and whose fault it is.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A request, a file it names or the output folder was not what the call allows.
    #[error("{0}")]
    Input(String),
    /// The call failed after accepting its input (an encoder, a full disk).
    #[error("{0}")]
    Internal(String),
    /// An output folder could not be prepared or written (the caller's `--out`).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

impl StudyError {
    /// The caller's input.
    pub fn input(message: impl Into<String>) -> Self {
        Self::Input(message.into())
    }

    /// The program's fault.
    pub fn internal(message: impl Into<String>) -> Self {
        Self::Internal(message.into())
    }
}

/// Why `what` is refused in a build without the `rig` feature (the README's first command
/// builds sandjumper-cli without it): bad input, saying how to build it.
pub fn without_rig(what: &str) -> String {
    format!(
        "{what}: this build has no rig (built with --no-default-features; build sandjumper-cli \
         with its default features, or with --features rig)"
    )
}

impl Blamed for StudyError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) | Self::Output(_) => Blame::Input,
            Self::Internal(_) | Self::Plot(_) => Blame::Internal,
        }
    }
}

impl From<sandjumper_model::resolve::ResolveError> for StudyError {
    fn from(e: sandjumper_model::resolve::ResolveError) -> Self {
        Self::Input(e.to_string())
    }
}
