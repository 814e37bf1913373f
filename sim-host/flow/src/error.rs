//! What can go wrong in a PIV run ([`crate::run`]) or a synthetic sequence
//! ([`crate::piv_synthetic`]), and whose fault it is.

use sandjumper_output::plot::PlotError;
use sandjumper_output::{Blame, Blamed, OutputError};

/// A failed `piv` or `piv-synthetic` call. The messages are the command line's.
#[derive(Debug, thiserror::Error)]
pub enum FlowError {
    /// The request, or a file it names (frames, mask, foot outlines, log, image), is not what
    /// a run allows.
    #[error("{0}")]
    Input(String),
    /// The output folder could not be claimed or written (the caller's path: input).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The run failed after accepting its input (encoding a summary, writing a table).
    #[error("{0}")]
    Internal(String),
}

impl FlowError {
    /// An [`FlowError::Input`] from anything printable.
    pub(crate) fn input(e: impl std::fmt::Display) -> Self {
        Self::Input(e.to_string())
    }

    /// An [`FlowError::Internal`] from anything printable.
    pub(crate) fn internal(e: impl std::fmt::Display) -> Self {
        Self::Internal(e.to_string())
    }
}

impl Blamed for FlowError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) | Self::Output(_) => Blame::Input,
            Self::Plot(_) | Self::Internal(_) => Blame::Internal,
        }
    }
}
