//! Slurm's options on the command line and `dem lammps --slurm`'s submission, over
//! [`sandjumper_slurm`] (the job's folder, its script, `sbatch`, `squeue`, `scontrol`).
//!
//! Two commands submit: `sweep --slurm N` (a job array, one shard per task:
//! `crate::study::sweep::slurm`) and `dem lammps --slurm` (one job of `--ranks` MPI tasks:
//! [`submit_job`]).

use std::path::Path;

use clap::Args;

use crate::study::cli_error;
use sandjumper_output::CliError;
use sandjumper_slurm::{self as slurm, JobScript, QueueOptions, quote};

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
/// `--out` and `--ranks`) as one job of `tasks` tasks writing `out`; wait for it (unless
/// told not to) and check that it succeeded and wrote `expect` into `out`. A job that
/// failed, timed out or was cancelled is reported with the tail of its log, exit status 1.
pub fn submit_job(
    name: &str,
    command: &[&str],
    tasks: u32,
    out: &Path,
    expect: &[&str],
    s: &JobArgs,
) -> Result<(), CliError> {
    slurm::tool("sbatch", "--slurm").map_err(cli_error)?;
    let dir = slurm::fresh_job_dir(out).map_err(cli_error)?;
    let (exe, cwd) = slurm::program_and_cwd().map_err(cli_error)?;
    let argv = slurm::arguments().map_err(cli_error)?;
    let args = slurm::passed_on(
        &argv,
        command,
        &["--out", "--ranks", "--slurm-partition", "--slurm-time"],
        &["--slurm", "--slurm-no-wait"],
    );
    let out_abs = std::path::absolute(out)
        .map_err(|e| CliError::internal(format!("{}: {e}", out.display())))?;
    let script = JobScript {
        name: name.to_string(),
        shape: vec![format!("--ntasks={tasks}")],
        log: dir.join("logs").join("job.out"),
        cwd,
        queue: s.queue.options(),
        command: format!(
            "exec {} {} {} --ranks \"${{SLURM_NTASKS:-{tasks}}}\" --out {}\n",
            quote(&exe.to_string_lossy()),
            command.join(" "),
            args.iter().map(|a| quote(a)).collect::<Vec<_>>().join(" "),
            quote(&out_abs.to_string_lossy())
        ),
    };
    let job = slurm::submit(&dir, &script).map_err(cli_error)?;
    eprintln!(
        "submitted Slurm job {} ({tasks} task(s)); script and log in {}",
        job.id,
        dir.display()
    );
    if s.queue.slurm_no_wait {
        println!("{}", job.id);
        eprintln!("when it is done its output is in {}", out.display());
        return Ok(());
    }
    job.wait().map_err(cli_error)?;
    let complete = expect.iter().all(|f| out.join(f).is_file());
    if let Some((st, code)) = job.unsuccessful(None, complete) {
        let log = dir.join("logs").join("job.out");
        return Err(CliError::internal(format!(
            "Slurm job {}: {st}, exit code {code}, output {}; log {}:\n    {}",
            job.id,
            if complete { "written" } else { "missing" },
            log.display(),
            slurm::log_tail(&log, 8)
        )));
    }
    eprintln!("Slurm job {} done: {}", job.id, out.display());
    Ok(())
}
