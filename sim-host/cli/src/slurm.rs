//! Slurm's options on the command line, as [`sandjumper_slurm`]'s [`QueueOptions`].
//!
//! Two commands submit: `sweep --slurm N` (a job array, one shard per task:
//! `crate::study::sweep`) and `dem lammps --slurm` (one job of `--ranks` MPI tasks:
//! `sandjumper_lammps::run::submit`).

use clap::Args;

use sandjumper_slurm::QueueOptions;

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
    /// Nodes to spread the job's tasks over (default: as Slurm places them).
    #[arg(long, value_name = "N", requires = "slurm", value_parser = clap::value_parser!(u32).range(1..))]
    pub slurm_nodes: Option<u32>,
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
            nodes: self.slurm_nodes,
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

/// This program's path, which a Slurm job runs again on the cluster.
pub fn this_program() -> Result<std::path::PathBuf, crate::command::CliError> {
    std::env::current_exe()
        .map_err(|e| crate::command::CliError::internal(format!("cannot find this program: {e}")))
}
