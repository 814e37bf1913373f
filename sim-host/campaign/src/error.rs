//! What a campaign session's calls return when they fail.

use sandjumper_output::{Blame, Blamed};

/// A campaign call failed: the message says what, where and what is allowed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CampaignError {
    /// The request, the campaign file, the output folder or the link was not what a
    /// campaign allows (the command line's exit status 2).
    #[error("{0}")]
    Input(String),
    /// The session failed after accepting its input: a journal or folder it could not
    /// write, or a point that stopped the campaign by its failure policy (exit status 1).
    #[error("{0}")]
    Internal(String),
}

impl CampaignError {
    /// The caller's input, from any message.
    pub fn input(message: impl std::fmt::Display) -> Self {
        Self::Input(message.to_string())
    }

    /// The session's own failure, from any message.
    pub fn internal(message: impl std::fmt::Display) -> Self {
        Self::Internal(message.to_string())
    }
}

impl Blamed for CampaignError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) => Blame::Input,
            Self::Internal(_) => Blame::Internal,
        }
    }
}
