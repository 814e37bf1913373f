//! `sandjumper rig flash`: write the F407 firmware with the probe-rs CLI (an external
//! program): a face over [`sandjumper_rig::tool::flash`].

use std::path::PathBuf;

use clap::Args;

use super::TargetArgs;
use crate::command::CliError;
use sandjumper_output::Silent;
use sandjumper_rig::tool::flash::{FlashRequest, flash};

/// `rig flash`.
#[derive(Debug, Clone, Args)]
pub struct FlashArgs {
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// The probe-rs executable.
    #[arg(long, value_name = "PATH", default_value = "probe-rs")]
    pub probe_rs: PathBuf,
}

/// Run `rig flash`.
pub fn run(a: &FlashArgs) -> Result<(), CliError> {
    let request = FlashRequest {
        target: a.target.target(),
        probe_rs: a.probe_rs.clone(),
    };
    print!("{}", flash(&request, &Silent)?);
    Ok(())
}
