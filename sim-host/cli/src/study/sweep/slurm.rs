//! `sweep --slurm N`: the sweep as a Slurm job array, one shard per task.
//!
//! 1. Write `DIR.slurm/job.sbatch`: `#SBATCH --array=1-N`, each task running this very
//!    program with the sweep's own arguments plus `--shard $SLURM_ARRAY_TASK_ID/N --threads
//!    $SLURM_CPUS_PER_TASK --out DIR.slurm/shard-$SLURM_ARRAY_TASK_ID` (shards are numbered
//!    from 1, as array tasks are); each task's output in `DIR.slurm/logs/task-I.out`.
//! 2. Submit it with `sbatch --parsable`; print the job id.
//! 3. With `--slurm-no-wait`, stop there and print the `merge` command. Otherwise wait until
//!    no task is pending or running (`squeue`), then check every task: its shard directory
//!    complete, and its final state and exit code (`scontrol`, while Slurm remembers it).
//!    A task that failed, was cancelled or timed out is reported with the tail of its log and
//!    nothing is merged (exit status 1); when all succeeded the shards are merged into DIR as
//!    `sandjumper merge` does.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::command::CliError;
use sandjumper_slurm::{self as slurm, JobScript, quote};

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

/// The sweep's own arguments (after `sweep`) without the ones each task sets itself:
/// `--out`, `--shard`, `--threads` and every `--slurm*`.
fn task_arguments(argv: &[String]) -> Vec<String> {
    slurm::passed_on(
        argv,
        &["sweep"],
        &[
            "--out",
            "--shard",
            "--threads",
            "--slurm",
            "--slurm-partition",
            "--slurm-time",
            "--slurm-cpus",
        ],
        &["--slurm-no-wait"],
    )
}

/// Submit the sweep `argv` asks for as a job array; unless told not to, wait for it: the
/// shard directories to merge into `out` (None: not waited for).
pub fn submit(
    argv: &[String],
    out: &Path,
    s: &SlurmArgs,
) -> Result<Option<Vec<PathBuf>>, CliError> {
    let tasks = s.slurm.unwrap_or(1);
    slurm::tool("sbatch", "--slurm")?;
    let dir = slurm::fresh_job_dir(out)?;
    let (exe, cwd) = slurm::program_and_cwd()?;
    let script = JobScript {
        name: "sweep".into(),
        shape: vec![
            format!("--array=1-{tasks}"),
            format!("--cpus-per-task={}", s.slurm_cpus),
        ],
        log: dir.join("logs").join("task-%a.out"),
        cwd,
        queue: s.queue.options(),
        command: format!(
            "exec {} sweep {} --shard \"$SLURM_ARRAY_TASK_ID/{tasks}\" --threads \
             \"${{SLURM_CPUS_PER_TASK:-1}}\" --out {}/shard-\"$SLURM_ARRAY_TASK_ID\"\n",
            quote(&exe.to_string_lossy()),
            task_arguments(argv)
                .iter()
                .map(|a| quote(a))
                .collect::<Vec<_>>()
                .join(" "),
            quote(&dir.to_string_lossy())
        ),
    };
    let job = slurm::submit(&dir, &script)?;
    eprintln!(
        "submitted Slurm job {} (array 1-{tasks}, {} CPU(s) each); script and logs in {}",
        job.id,
        s.slurm_cpus,
        dir.display()
    );
    if s.queue.slurm_no_wait {
        println!("{}", job.id);
        eprintln!(
            "when it is done: sandjumper merge {}/shard-* --out {}",
            dir.display(),
            out.display()
        );
        return Ok(None);
    }
    job.wait()?;
    let shards: Vec<PathBuf> = (1..=tasks)
        .map(|i| dir.join(format!("shard-{i}")))
        .collect();
    let mut failed = Vec::new();
    for (i, shard) in (1..=tasks).zip(&shards) {
        let complete = shard.join("sweep.toml").is_file();
        if let Some((st, code)) = job.unsuccessful(Some(i), complete) {
            let log = dir.join("logs").join(format!("task-{i}.out"));
            failed.push(format!(
                "task {i}: {st}, exit code {code}, shard {}; log {}:\n    {}",
                if complete { "written" } else { "missing" },
                log.display(),
                slurm::log_tail(&log, 5)
            ));
        }
    }
    if !failed.is_empty() {
        return Err(CliError::internal(format!(
            "Slurm job {}: {} of {tasks} task(s) did not succeed; nothing merged (fix and \
             resubmit, or merge the good shards by hand)\n{}",
            job.id,
            failed.len(),
            failed.join("\n")
        )));
    }
    eprintln!("all {tasks} task(s) of job {} done; merging", job.id);
    Ok(Some(shards))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_task_gets_the_sweeps_arguments_without_the_ones_it_sets() {
        let argv: Vec<String> = [
            "sandjumper",
            "sweep",
            "--kind",
            "single",
            "--out",
            "x",
            "--slurm",
            "3",
            "--slurm-time=5",
            "--freq",
            "8:12:1",
            "--threads",
            "2",
            "--slurm-no-wait",
            "--shard=1/2",
            "--slurm-cpus",
            "2",
            "--phi",
            "0.57",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        assert_eq!(
            task_arguments(&argv),
            ["--kind", "single", "--freq", "8:12:1", "--phi", "0.57"]
        );
    }
}
