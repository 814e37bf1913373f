//! Slurm's options on the command line and `dem lammps --slurm`'s submission, over
//! [`sandjumper_slurm`] (the job's folder, its script, `sbatch`, `squeue`, `scontrol`).
//!
//! Two commands submit: `sweep --slurm N` (a job array, one shard per task:
//! `crate::study::sweep`) and `dem lammps --slurm` (one job of `--ranks` MPI tasks:
//! [`submit_job`]).

use std::path::Path;

use clap::Args;

use crate::command::CliError;
use crate::command::progress::Bars;
use sandjumper_slurm::{self as slurm, QueueOptions};

/// The queue options every submitting command has (each requires its `--slurm`).
#[derive(Debug, Clone, Args)]
pub struct QueueArgs {
    /// Partition to submit to (default: the cluster's default).
    #[arg(long, value_name = "NAME", requires = "slurm")]
    pub slurm_partition: Option<String>,
    /// Time limit of the job (of each array task) in Slurm's format, e.g. 30, 1:00:00,
    /// 2-00:00:00.
    #[arg(
        long,
        value_name = "TIME",
        default_value = "1:00:00",
        requires = "slurm"
    )]
    pub slurm_time: String,
    /// Submit and return the job id without waiting.
    #[arg(long, requires = "slurm")]
    pub slurm_no_wait: bool,
}

impl QueueArgs {
    /// The library's queue options.
    pub fn options(&self) -> QueueOptions {
        QueueOptions {
            partition: self.slurm_partition.clone(),
            time: self.slurm_time.clone(),
            no_wait: self.slurm_no_wait,
        }
    }
}

/// The Slurm options of a command submitted as one job.
#[derive(Debug, Clone, Args)]
pub struct JobArgs {
    /// Submit to Slurm as one job of --ranks tasks, wait for it and check its output.
    #[arg(long)]
    pub slurm: bool,
    /// Partition, time limit, waiting.
    #[command(flatten)]
    pub queue: QueueArgs,
}

/// Submit this very command (the words `command`, its arguments without the Slurm options,
/// `--out` and `--ranks`) as one job of `tasks` tasks writing `out`
/// ([`sandjumper_slurm::submit_command`]); without waiting, print the job's id.
pub fn submit_job(
    name: &str,
    command: &[&str],
    tasks: u32,
    out: &Path,
    expect: &[&str],
    s: &JobArgs,
) -> Result<(), CliError> {
    let job = slurm::CommandJob {
        name,
        command,
        tasks,
        out,
        expect,
        queue: s.queue.options(),
    };
    if let slurm::CommandJobOutcome::Queued { id } = slurm::submit_command(&job, &Bars::new())? {
        println!("{id}");
        eprintln!("when it is done its output is in {}", out.display());
    }
    Ok(())
}
