//! `sandjumper merge`: join the shard directories of one sweep.

use super::command::{write_sweep_files, write_sweep_plots};
use clap::Args;
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_study::sweep::merge::{merge_shards, read_sweep_dir};
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
    let out_canon = std::fs::canonicalize(&a.out).ok();
    let mut shards = Vec::with_capacity(a.dirs.len());
    for dir in &a.dirs {
        if out_canon.is_some() && std::fs::canonicalize(dir).ok() == out_canon {
            return Err(CliError::input(format!(
                "--out `{}` is one of the shard directories: write the merged sweep elsewhere",
                a.out.display()
            )));
        }
        shards.push(read_sweep_dir(dir).map_err(|e| CliError::input(e.0))?);
    }
    let first_dir = shards[0].dir.clone();
    let (meta, outcome) = merge_shards(shards).map_err(|e| CliError::input(e.0))?;
    let staged = StagedDir::create(&a.out)?;
    write_sweep_files(staged.path(), &meta, &outcome)?;
    // The parameter files are identical in every shard (they are part of the spec hash).
    let entries = std::fs::read_dir(&first_dir)
        .map_err(|e| CliError::input(format!("cannot read `{}`: {e}", first_dir.display())))?;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with("params") && name.ends_with(".toml") {
            std::fs::copy(entry.path(), staged.file(&name)).map_err(|e| {
                CliError::internal(format!("cannot copy `{}`: {e}", entry.path().display()))
            })?;
        }
    }
    let plots = write_sweep_plots(staged.path(), &outcome)?;
    let dir = staged.commit()?;
    eprintln!(
        "merged {} shard(s): {} rows, {} failures; wrote {}/ (sweep.csv, failures.csv, sweep.toml, params{})",
        a.dirs.len(),
        outcome.rows.len(),
        outcome.failures.len(),
        dir.display(),
        plots.iter().map(|p| format!(", {p}")).collect::<String>()
    );
    if !outcome.failures.is_empty() {
        eprintln!(
            "warning: {} jump(s) of the sweep failed; see failures.csv",
            outcome.failures.len()
        );
    }
    Ok(())
}
