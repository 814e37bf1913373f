//! What the `dem` subcommands share: `--episode`, a share's parser, a library error as the
//! command line's, JSON on stdout.

use crate::command::CliError;
use sandjumper_dem::intrude_run::Episode;

use crate::command::args::parse_number;

/// A share in 0..=1.
pub(crate) fn parse_share(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("`{s}` not allowed (allowed: 0 to 1)"))
    }
}

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

pub use crate::command::progress::cli_error;

/// Print `value` as pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> Result<(), CliError> {
    let text =
        serde_json::to_string_pretty(value).map_err(|e| CliError::internal(e.to_string()))?;
    println!("{text}");
    Ok(())
}
