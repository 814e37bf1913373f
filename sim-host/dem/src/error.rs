//! What a DEM run returns when it fails: the message the command line prints and whose
//! fault it is ([`Blame`]).

use sandjumper_output::{Blame, Blamed, OutputError};

/// A DEM request refused or a DEM run failed.
#[derive(Debug, thiserror::Error)]
pub enum DemError {
    /// The request, a file it names or the output folder is not what the run allows (the
    /// command line's exit status 2).
    #[error("{0}")]
    Input(String),
    /// The run failed after accepting its input: a file that could not be written, a thread
    /// pool that did not start (exit status 1).
    #[error("{0}")]
    Internal(String),
}

impl DemError {
    /// Bad input, with its message.
    pub fn input(message: impl Into<String>) -> Self {
        Self::Input(message.into())
    }

    /// An internal failure, with its message.
    pub fn internal(message: impl std::fmt::Display) -> Self {
        Self::Internal(message.to_string())
    }
}

impl Blamed for DemError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) => Blame::Input,
            Self::Internal(_) => Blame::Internal,
        }
    }
}

/// An output folder that cannot be created or committed is the caller's (its path).
impl From<OutputError> for DemError {
    fn from(e: OutputError) -> Self {
        Self::Input(e.to_string())
    }
}

/// A figure that cannot be drawn is the program's.
impl From<sandjumper_output::plot::PlotError> for DemError {
    fn from(e: sandjumper_output::plot::PlotError) -> Self {
        Self::Internal(e.to_string())
    }
}
