//! What `figures dem` returns when it fails: the message and whose fault it is.

use sandjumper_output::{Blame, Blamed, OutputError};

/// A `figures dem` request refused, or one of its stages failed.
#[derive(Debug, thiserror::Error)]
pub enum FiguresDemError {
    /// The request (or a stage's input) is not what the call allows (exit status 2).
    #[error("{0}")]
    Input(String),
    /// A stage or a file failed after the input was accepted (exit status 1).
    #[error("{0}")]
    Internal(String),
}

impl FiguresDemError {
    /// Bad input, with its message.
    pub fn input(message: impl Into<String>) -> Self {
        Self::Input(message.into())
    }

    /// An internal failure, with its message.
    pub fn internal(message: impl std::fmt::Display) -> Self {
        Self::Internal(message.to_string())
    }

    /// A stage's error (any [`Blamed`] error) with the stage's command line before its
    /// message, its blame kept.
    pub fn of_stage<E: Blamed>(command: &str, e: &E) -> Self {
        let message = format!("{command}: {e}");
        match e.blame() {
            Blame::Input => Self::Input(message),
            Blame::Internal => Self::Internal(message),
        }
    }
}

impl Blamed for FiguresDemError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) => Blame::Input,
            Self::Internal(_) => Blame::Internal,
        }
    }
}

/// An output folder that cannot be created or committed is the caller's (its path).
impl From<OutputError> for FiguresDemError {
    fn from(e: OutputError) -> Self {
        Self::Input(e.to_string())
    }
}

/// A figure that cannot be drawn is the program's.
impl From<sandjumper_output::plot::PlotError> for FiguresDemError {
    fn from(e: sandjumper_output::plot::PlotError) -> Self {
        Self::Internal(e.to_string())
    }
}
