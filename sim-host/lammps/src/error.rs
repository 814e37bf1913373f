//! What a LAMMPS run or read-back returns when it fails: the message the command line
//! prints and whose fault it is ([`Blame`]).

use sandjumper_output::{Blame, Blamed, OutputError};

/// A `dem lammps` request refused, or its run or read-back failed.
#[derive(Debug, thiserror::Error)]
pub enum LammpsError {
    /// The request, a file it names, LAMMPS not found or a run folder of another run (the
    /// command line's exit status 2).
    #[error("{0}")]
    Input(String),
    /// The run failed after accepting its input: LAMMPS crashed, a file could not be
    /// written (exit status 1).
    #[error("{0}")]
    Internal(String),
}

impl LammpsError {
    /// Bad input, with its message.
    pub fn input(message: impl Into<String>) -> Self {
        Self::Input(message.into())
    }

    /// An internal failure, with its message.
    pub fn internal(message: impl std::fmt::Display) -> Self {
        Self::Internal(message.to_string())
    }

    /// The same error (the same blame) with its message changed by `f`.
    pub fn map_message(self, f: impl FnOnce(String) -> String) -> Self {
        match self {
            Self::Input(m) => Self::Input(f(m)),
            Self::Internal(m) => Self::Internal(f(m)),
        }
    }
}

impl Blamed for LammpsError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) => Blame::Input,
            Self::Internal(_) => Blame::Internal,
        }
    }
}

/// An output folder that cannot be created or committed is the caller's (its path).
impl From<OutputError> for LammpsError {
    fn from(e: OutputError) -> Self {
        Self::Input(e.to_string())
    }
}

/// A Slurm submission's failure keeps its message and its blame.
impl From<sandjumper_slurm::SlurmError> for LammpsError {
    fn from(e: sandjumper_slurm::SlurmError) -> Self {
        match e {
            sandjumper_slurm::SlurmError::Input(m) => Self::Input(m),
            sandjumper_slurm::SlurmError::Internal(m) => Self::Internal(m),
        }
    }
}
