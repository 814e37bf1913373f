//! What can go wrong in a rig call, and whose fault it is ([`Blamed`]): the command line maps
//! [`Blame::Input`] to exit status 2 and [`Blame::Internal`] to 1.

use std::path::PathBuf;

use sandjumper_output::plot::PlotError;
use sandjumper_output::{Blame, Blamed, OutputError};

use crate::protocol::link::LinkError;

/// Why a rig call (`hil`, a rig tool program) failed. Every message is the one the command
/// line prints after `error: `.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The request, a file it names, the link or the controller's refusal: the caller's to fix
    /// (the words say what and what is allowed).
    #[error("{0}")]
    Input(String),
    /// The call failed after accepting its input (a bug, an encoding, a file that cannot be
    /// written).
    #[error("{0}")]
    Internal(String),
    /// A link failed during `what` (the controller's refusals and a bad port are bad input,
    /// like every other failure of a run).
    #[error("{what} through {link} failed: {source}")]
    Link {
        /// The link's name (`sil`, `pil`, `f407`, the port).
        link: String,
        /// What was under way ("the jump", "status query").
        what: String,
        /// The link's error.
        #[source]
        source: LinkError,
    },
    /// The output folder (exists, cannot be staged or committed).
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The controller did not complete the program cleanly (a fault, or no `Done`): the
    /// outputs were written, `summary` says what happened.
    #[error("the {what} did not complete cleanly (see {})", summary.display())]
    NotCompleted {
        /// "jump", "replay", "intrusion".
        what: String,
        /// The written summary.json.
        summary: PathBuf,
    },
}

impl RigError {
    /// Bad input (exit status 2).
    pub fn input(message: impl Into<String>) -> Self {
        Self::Input(message.into())
    }

    /// An internal failure (exit status 1).
    pub fn internal(message: impl Into<String>) -> Self {
        Self::Internal(message.into())
    }

    /// A link failure during `what` on the link `link`.
    pub fn link(link: &str, what: &str, source: LinkError) -> Self {
        Self::Link {
            link: link.to_string(),
            what: what.to_string(),
            source,
        }
    }
}

impl Blamed for RigError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) | Self::Link { .. } | Self::Output(_) => Blame::Input,
            Self::Internal(_) | Self::Plot(_) | Self::NotCompleted { .. } => Blame::Internal,
        }
    }
}

/// Encode `value` as pretty JSON (`what`: "the summary", "the status").
pub fn to_json<T: serde::Serialize>(value: &T, what: &str) -> Result<String, RigError> {
    serde_json::to_string_pretty(value)
        .map_err(|e| RigError::internal(format!("cannot encode {what} as JSON: {e}")))
}
