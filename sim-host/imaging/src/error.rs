//! What can go wrong in `track` ([`crate::run`]) or `camera-scale` ([`crate::camera_scale`]),
//! and whose fault it is.

use sandjumper_output::plot::PlotError;
use sandjumper_output::{Blame, Blamed, OutputError};

/// A failed `track` or `camera-scale` call. The messages are the command line's.
#[derive(Debug, thiserror::Error)]
pub enum ImagingError {
    /// The request, or a file it names (frames, log), is not what a call allows.
    #[error("{0}")]
    Input(String),
    /// The output folder could not be claimed or written (the caller's path: input).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The call failed after accepting its input (encoding a summary, writing a table).
    #[error("{0}")]
    Internal(String),
}

impl ImagingError {
    /// An [`ImagingError::Input`] from anything printable.
    pub(crate) fn input(e: impl std::fmt::Display) -> Self {
        Self::Input(e.to_string())
    }
}

impl Blamed for ImagingError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) | Self::Output(_) => Blame::Input,
            Self::Plot(_) | Self::Internal(_) => Blame::Internal,
        }
    }
}
