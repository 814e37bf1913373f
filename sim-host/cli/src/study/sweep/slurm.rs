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
use std::process::Command;
use std::time::Duration;

use clap::Args;

use sandjumper_output::CliError;

/// The Slurm options of `sweep`.
#[derive(Debug, Clone, Args)]
pub struct SlurmArgs {
    /// Submit the sweep to Slurm as a job array of N tasks (one shard each), wait for it and
    /// merge the shards into --out.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub slurm: Option<u32>,
    /// Partition to submit to (default: the cluster's default).
    #[arg(long, value_name = "NAME", requires = "slurm")]
    pub slurm_partition: Option<String>,
    /// Time limit of each task (Slurm's format, e.g. 30, 1:00:00, 2-00:00:00).
    #[arg(
        long,
        value_name = "TIME",
        default_value = "1:00:00",
        requires = "slurm"
    )]
    pub slurm_time: String,
    /// CPUs of each task (its sweep's threads).
    #[arg(long, value_name = "N", default_value = "1", requires = "slurm",
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub slurm_cpus: u32,
    /// Submit and return the job id without waiting (merge the shards later with the
    /// printed `sandjumper merge` command).
    #[arg(long, requires = "slurm")]
    pub slurm_no_wait: bool,
}

/// The job's directory beside `out`: `DIR.slurm`.
pub fn job_dir(out: &Path) -> PathBuf {
    let mut name = out
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".slurm");
    out.with_file_name(name)
}

/// `s` quoted for a POSIX shell.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The sweep's own arguments (after `sweep`) without the ones each task sets itself:
/// `--out`, `--shard`, `--threads` and every `--slurm*`.
fn task_arguments(argv: &[String]) -> Vec<String> {
    let with_value = [
        "--out",
        "--shard",
        "--threads",
        "--slurm",
        "--slurm-partition",
        "--slurm-time",
        "--slurm-cpus",
    ];
    let mut out = Vec::new();
    let mut it = argv.iter().skip_while(|a| a.as_str() != "sweep").skip(1);
    while let Some(a) = it.next() {
        let name = a.split('=').next().unwrap_or(a);
        if a == "--slurm-no-wait" {
            continue;
        }
        if with_value.contains(&name) {
            if !a.contains('=') {
                it.next();
            }
            continue;
        }
        out.push(a.clone());
    }
    out
}

fn tool(name: &str) -> Result<(), CliError> {
    match Command::new(name).arg("--version").output() {
        Ok(o) if o.status.success() => Ok(()),
        _ => Err(CliError::input(format!(
            "--slurm needs Slurm's `{name}` on PATH (not found or not working here); run the \
             sweep on a cluster's login node, or without --slurm"
        ))),
    }
}

fn run_tool(cmd: &mut Command, what: &str) -> Result<String, CliError> {
    let o = cmd
        .output()
        .map_err(|e| CliError::internal(format!("cannot run {what}: {e}")))?;
    if !o.status.success() {
        return Err(CliError::internal(format!(
            "{what} failed ({}): {}",
            o.status,
            String::from_utf8_lossy(&o.stderr).trim()
        )));
    }
    Ok(String::from_utf8_lossy(&o.stdout).into_owned())
}

/// One task's final state and exit code, from `scontrol show job ID_I` (the record whose
/// `ArrayTaskId` is the task: Slurm may answer with the array's other records); None when
/// Slurm has none (a task cancelled before it started, or one forgotten after `MinJobAge`).
fn task_state(job: &str, task: u32) -> Option<(String, String)> {
    let o = Command::new("scontrol")
        .args(["show", "job", "-o", &format!("{job}_{task}")])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let want = task.to_string();
    text.lines().find_map(|line| {
        let field = |k: &str| {
            line.split_whitespace()
                .find_map(|w| w.strip_prefix(k))
                .map(str::to_string)
        };
        (field("ArrayTaskId=")? == want).then_some(())?;
        Some((field("JobState=")?, field("ExitCode=").unwrap_or_default()))
    })
}

/// The last `n` lines of a task's log.
fn log_tail(path: &Path, n: usize) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n    ")
}

/// Submit the sweep `argv` asks for as a job array, and (unless told not to) wait for it and
/// merge its shards into `out`.
pub fn submit(argv: &[String], out: &Path, s: &SlurmArgs) -> Result<(), CliError> {
    let tasks = s.slurm.unwrap_or(1);
    tool("sbatch")?;
    let dir = job_dir(out);
    if dir.exists() {
        if !dir.join("job.sbatch").is_file() {
            return Err(CliError::input(format!(
                "{} exists and is not a sandjumper Slurm job directory: remove it or choose \
                 another --out",
                dir.display()
            )));
        }
        std::fs::remove_dir_all(&dir)
            .map_err(|e| CliError::internal(format!("cannot clear {}: {e}", dir.display())))?;
    }
    std::fs::create_dir_all(dir.join("logs"))
        .map_err(|e| CliError::input(format!("cannot create {}: {e}", dir.display())))?;
    let dir = std::fs::canonicalize(&dir)
        .map_err(|e| CliError::internal(format!("{}: {e}", dir.display())))?;
    let exe = std::env::current_exe()
        .map_err(|e| CliError::internal(format!("cannot find this program: {e}")))?;
    let cwd = std::env::current_dir()
        .map_err(|e| CliError::internal(format!("no working directory: {e}")))?;
    let mut script = String::from("#!/bin/bash\n");
    script += &format!("#SBATCH --job-name=sandjumper-sweep\n#SBATCH --array=1-{tasks}\n");
    script += &format!("#SBATCH --cpus-per-task={}\n", s.slurm_cpus);
    script += &format!("#SBATCH --time={}\n", s.slurm_time);
    script += &format!("#SBATCH --output={}/logs/task-%a.out\n", dir.display());
    script += &format!("#SBATCH --chdir={}\n", cwd.display());
    if let Some(p) = &s.slurm_partition {
        script += &format!("#SBATCH --partition={p}\n");
    }
    script += "set -euo pipefail\n";
    script += &format!(
        "exec {} sweep {} --shard \"$SLURM_ARRAY_TASK_ID/{tasks}\" --threads \
         \"${{SLURM_CPUS_PER_TASK:-1}}\" --out {}/shard-\"$SLURM_ARRAY_TASK_ID\"\n",
        quote(&exe.to_string_lossy()),
        task_arguments(argv)
            .iter()
            .map(|a| quote(a))
            .collect::<Vec<_>>()
            .join(" "),
        quote(&dir.to_string_lossy())
    );
    let sbatch = dir.join("job.sbatch");
    std::fs::write(&sbatch, &script)
        .map_err(|e| CliError::internal(format!("cannot write {}: {e}", sbatch.display())))?;
    let job = run_tool(
        Command::new("sbatch").arg("--parsable").arg(&sbatch),
        "sbatch",
    )?;
    let job = job.trim().split(';').next().unwrap_or("").to_string();
    if job.is_empty() {
        return Err(CliError::internal("sbatch printed no job id"));
    }
    eprintln!(
        "submitted Slurm job {job} (array 1-{tasks}, {} CPU(s) each); script and logs in {}",
        s.slurm_cpus,
        dir.display()
    );
    let shards: Vec<PathBuf> = (1..=tasks)
        .map(|i| dir.join(format!("shard-{i}")))
        .collect();
    if s.slurm_no_wait {
        println!("{job}");
        eprintln!(
            "when it is done: sandjumper merge {}/shard-* --out {}",
            dir.display(),
            out.display()
        );
        return Ok(());
    }
    // Wait until no task is pending, running or completing.
    loop {
        let queued = run_tool(
            Command::new("squeue").args(["-h", "-j", &job, "-o", "%i %T"]),
            "squeue",
        )?;
        if queued.trim().is_empty() {
            break;
        }
        std::thread::sleep(Duration::from_millis(500));
    }
    let mut failed = Vec::new();
    for (i, shard) in (1..=tasks).zip(&shards) {
        let state = task_state(&job, i);
        let complete = shard.join("sweep.toml").is_file();
        let ok_state = state
            .as_ref()
            .is_none_or(|(st, code)| st == "COMPLETED" && code == "0:0");
        if !complete || !ok_state {
            let (st, code) = state.unwrap_or_else(|| {
                (
                    "no record (cancelled before it started, or forgotten by Slurm)".into(),
                    "none".into(),
                )
            });
            let log = dir.join("logs").join(format!("task-{i}.out"));
            failed.push(format!(
                "task {i}: {st}, exit code {code}, shard {}; log {}:\n    {}",
                if complete { "written" } else { "missing" },
                log.display(),
                log_tail(&log, 5)
            ));
        }
    }
    if !failed.is_empty() {
        return Err(CliError::internal(format!(
            "Slurm job {job}: {} of {tasks} task(s) did not succeed; nothing merged (fix and \
             resubmit, or merge the good shards by hand)\n{}",
            failed.len(),
            failed.join("\n")
        )));
    }
    eprintln!("all {tasks} task(s) of job {job} done; merging");
    super::merge_command::run(&super::merge_command::MergeArgs {
        dirs: shards,
        out: out.to_path_buf(),
    })
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
        assert_eq!(quote("a'b"), r"'a'\''b'");
        assert_eq!(job_dir(Path::new("/t/run")), Path::new("/t/run.slurm"));
    }
}
