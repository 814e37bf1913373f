//! What the `dem` subcommands share: `--episode` and JSON on stdout.

use crate::command::CliError;
use sandjumper_dem::intrude_run::Episode;

/// `--episode`: a part of a jump's trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EpisodeChoice {
    /// The foot's last intrusion before the jump's flight.
    PushOff,
}

impl From<EpisodeChoice> for Episode {
    fn from(e: EpisodeChoice) -> Self {
        match e {
            EpisodeChoice::PushOff => Episode::PushOff,
        }
    }
}

/// Print `value` as pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> Result<(), CliError> {
    let text =
        serde_json::to_string_pretty(value).map_err(|e| CliError::internal(e.to_string()))?;
    println!("{text}");
    Ok(())
}
