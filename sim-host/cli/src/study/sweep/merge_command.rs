//! `sandjumper merge`: join the shard directories of one sweep ([`sandjumper_study::sweep::merge()`]).

use crate::command::CliError;
use clap::Args;
use sandjumper_output::Silent;
use sandjumper_study::sweep::{MergeRequest, merge};
use std::path::PathBuf;

/// `sandjumper merge`.
#[derive(Debug, Clone, Args)]
pub struct MergeArgs {
    /// Shard directories written by `sandjumper sweep --shard I/N` (all N of them, any order).
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Output directory for the merged sweep.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Run `merge`.
pub fn run(a: &MergeArgs) -> Result<(), CliError> {
    merge_into(&MergeRequest {
        dirs: a.dirs.clone(),
        out: a.out.clone(),
    })
}

/// Merge the shards `request` names into its `out` and tell the user (also `sweep --slurm`'s
/// last step).
pub fn merge_into(request: &MergeRequest) -> Result<(), CliError> {
    let merged = merge(request, &Silent)?;
    let written = merged.write(&request.out)?;
    for line in merged.report(&written) {
        eprintln!("{line}");
    }
    Ok(())
}
