//! `sweep --slurm N`: the sweep as a Slurm job array, one shard per task
//! ([`sandjumper_slurm::submit_sharded`]); with `--slurm-no-wait` the job id and the `merge`
//! command are printed, otherwise, when every task succeeded, the shards are merged into DIR
//! as `sandjumper merge` does.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::command::CliError;
use crate::command::progress::Bars;
use sandjumper_slurm::{self as slurm, ShardedJob, ShardedJobOutcome};

/// The Slurm options of `sweep`.
#[derive(Debug, Clone, Args)]
pub struct SlurmArgs {
    /// Submit the sweep to Slurm as a job array of N tasks (one shard each), wait for it and
    /// merge the shards into --out.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub slurm: Option<u32>,
    /// CPUs of each task (its sweep's threads).
    #[arg(long, value_name = "N", default_value = "1", requires = "slurm",
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub slurm_cpus: u32,
    /// Partition, time limit of each task, waiting (merge the shards later with the printed
    /// `sandjumper merge` command).
    #[command(flatten)]
    pub queue: crate::slurm::QueueArgs,
}

/// Submit this sweep as a job array of `--slurm` tasks writing shards for `out`; unless told
/// not to, wait for it: the shard directories to merge into `out` (None: not waited for).
pub fn submit(out: &Path, s: &SlurmArgs) -> Result<Option<Vec<PathBuf>>, CliError> {
    let job = ShardedJob {
        name: "sweep",
        command: &["sweep"],
        tasks: s.slurm.unwrap_or(1),
        cpus: s.slurm_cpus,
        out,
        expect: "sweep.toml",
        queue: s.queue.options(),
    };
    match slurm::submit_sharded(&job, &Bars::new())? {
        ShardedJobOutcome::Queued { id, dir } => {
            println!("{id}");
            eprintln!(
                "when it is done: sandjumper merge {}/shard-* --out {}",
                dir.display(),
                out.display()
            );
            Ok(None)
        }
        ShardedJobOutcome::Done { id, shards } => {
            eprintln!("all {} task(s) of job {id} done; merging", shards.len());
            Ok(Some(shards))
        }
    }
}
