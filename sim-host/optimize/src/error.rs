//! What can go wrong in [`crate::run`]: the request, its checkpoint or its output folder
//! (the caller's input, exit status 2 on the command line), or the run itself (exit 1).

use sandjumper_output::plot::PlotError;
use sandjumper_output::{Blame, Blamed, OutputError};

/// An `optimize` run failed. The messages are the command line's, word for word.
#[derive(Debug, thiserror::Error)]
pub enum OptimizeError {
    /// The request breaks a limit (a flag out of range, a table rate that does not divide
    /// the control rate, a duration longer than the replay buffer holds, ...).
    #[error("{0}")]
    Invalid(String),
    /// No paper stroke of the sweep keeps the request's limits: there is no baseline.
    #[error(
        "none of the {points} paper strokes swept keeps the limits (stroke {stroke_m} m, peak \
         force {peak_force_n} N, duration {duration_s} s): loosen them"
    )]
    NoFeasiblePaperStroke {
        /// Points swept.
        points: usize,
        /// The stroke limit, m.
        stroke_m: f64,
        /// The drive's peak force, N.
        peak_force_n: f64,
        /// The duration limit, s.
        duration_s: f64,
    },
    /// The checkpoint beside the output folder cannot be used (made by another search, not a
    /// checkpoint, unreadable).
    #[error("{0}")]
    Checkpoint(String),
    /// The output folder cannot be prepared or written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The figure could not be drawn.
    #[error(transparent)]
    Figure(#[from] PlotError),
    /// The run failed after its input was accepted (a run through a link, the search, a
    /// file that could not be encoded, the threads).
    #[error("{0}")]
    Internal(String),
}

impl Blamed for OptimizeError {
    fn blame(&self) -> Blame {
        match self {
            Self::Invalid(_)
            | Self::NoFeasiblePaperStroke { .. }
            | Self::Checkpoint(_)
            | Self::Output(_) => Blame::Input,
            Self::Figure(_) | Self::Internal(_) => Blame::Internal,
        }
    }
}
