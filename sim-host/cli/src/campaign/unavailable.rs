//! `sandjumper campaign` in a build without the `campaign` feature: any arguments, refused
//! with exit status 2.

/// The command in a build without it.
pub mod command {
    use crate::command::CliError;
    use crate::command::unavailable::{Unbuilt, refuse};

    /// Whatever was given.
    pub type CampaignArgs = Unbuilt;

    /// Refuse: this build has no campaigns.
    pub fn run(_: &CampaignArgs) -> Result<(), CliError> {
        refuse("campaign", "campaigns", "campaign")
    }
}
