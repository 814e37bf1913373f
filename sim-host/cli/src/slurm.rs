//! Slurm, as the commands that submit to it share it: the job's directory beside the
//! output, arguments passed on to the job, `sbatch`, waiting with `squeue`, a job's or an
//! array task's final state from `scontrol`, the tail of a log.
//!
//! Two commands submit: `sweep --slurm N` (a job array, one shard per task:
//! `crate::study::sweep::slurm`) and `dem lammps --slurm` (one job of `--ranks` MPI tasks:
//! [`submit_job`]).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use clap::Args;

use sandjumper_output::CliError;

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
pub fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The command's own arguments (after the words `after`, e.g. `["dem", "lammps"]`) without
/// the options in `with_value` (and their values) and the flags in `flags`.
pub fn passed_on(
    argv: &[String],
    after: &[&str],
    with_value: &[&str],
    flags: &[&str],
) -> Vec<String> {
    let start = argv
        .windows(after.len())
        .position(|w| w.iter().zip(after).all(|(a, b)| a == b))
        .map_or(argv.len(), |i| i + after.len());
    let mut out = Vec::new();
    let mut it = argv[start..].iter();
    while let Some(a) = it.next() {
        let name = a.split('=').next().unwrap_or(a);
        if flags.contains(&a.as_str()) {
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

/// Refuse (exit 2) without Slurm's `name` on PATH.
pub fn tool(name: &str, option: &str) -> Result<(), CliError> {
    match Command::new(name).arg("--version").output() {
        Ok(o) if o.status.success() => Ok(()),
        _ => Err(CliError::input(format!(
            "{option} needs Slurm's `{name}` on PATH (not found or not working here); run on a \
             cluster's login node, or without {option}"
        ))),
    }
}

/// Run a Slurm tool; its stdout, or what it said when it failed.
pub fn run_tool(cmd: &mut Command, what: &str) -> Result<String, CliError> {
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

/// A job's (or with `task`, an array task's) final state and exit code, from `scontrol show
/// job` (for a task, the record whose `ArrayTaskId` is it: Slurm may answer with the array's
/// other records); None when Slurm has none (cancelled before it started, or forgotten after
/// `MinJobAge`).
pub fn job_state(job: &str, task: Option<u32>) -> Option<(String, String)> {
    let id = match task {
        Some(t) => format!("{job}_{t}"),
        None => job.to_string(),
    };
    let o = Command::new("scontrol")
        .args(["show", "job", "-o", &id])
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    text.lines().find_map(|line| {
        let field = |k: &str| {
            line.split_whitespace()
                .find_map(|w| w.strip_prefix(k))
                .map(str::to_string)
        };
        if let Some(t) = task {
            (field("ArrayTaskId=")? == t.to_string()).then_some(())?;
        }
        Some((field("JobState=")?, field("ExitCode=").unwrap_or_default()))
    })
}

/// How a job (or, with `task`, an array task) ended when it did not succeed: its state and
/// exit code; None when it succeeded and its output is `written`.
pub fn unsuccessful(job: &str, task: Option<u32>, written: bool) -> Option<(String, String)> {
    let state = job_state(job, task);
    let ok = state
        .as_ref()
        .is_none_or(|(st, code)| st == "COMPLETED" && code == "0:0");
    if written && ok {
        return None;
    }
    Some(state.unwrap_or_else(|| {
        (
            "no record (cancelled before it started, or forgotten by Slurm)".into(),
            "none".into(),
        )
    }))
}

/// The last `n` lines of a log, indented for a message.
pub fn log_tail(path: &Path, n: usize) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n    ")
}

/// Make `DIR.slurm` (with `logs/`) for `out`, replacing an earlier job directory of ours
/// unless its job (`job.id`) is still queued or running; its canonical path.
pub fn fresh_job_dir(out: &Path) -> Result<PathBuf, CliError> {
    let dir = job_dir(out);
    if dir.exists() {
        if !dir.join("job.sbatch").is_file() {
            return Err(CliError::input(format!(
                "{} exists and is not a sandjumper Slurm job directory: remove it or choose \
                 another --out",
                dir.display()
            )));
        }
        if let Ok(id) = std::fs::read_to_string(dir.join("job.id")) {
            let id = id.trim();
            // Unknown (no squeue, no controller) counts as queued: the folder stays.
            let queued = Command::new("squeue")
                .args(["-h", "-j", id, "-o", "%i"])
                .output()
                .map(|o| {
                    !o.status.success() || !String::from_utf8_lossy(&o.stdout).trim().is_empty()
                })
                .unwrap_or(true);
            if queued {
                return Err(CliError::input(format!(
                    "{}: its job {id} is still queued or running, or Slurm cannot say (allowed: a \
                     job directory whose job has ended; wait for it, or `scancel {id}`)",
                    dir.display()
                )));
            }
        }
        std::fs::remove_dir_all(&dir)
            .map_err(|e| CliError::internal(format!("cannot clear {}: {e}", dir.display())))?;
    }
    std::fs::create_dir_all(dir.join("logs"))
        .map_err(|e| CliError::input(format!("cannot create {}: {e}", dir.display())))?;
    std::fs::canonicalize(&dir).map_err(|e| CliError::internal(format!("{}: {e}", dir.display())))
}

/// This program's arguments as text (exit 2 naming one that is not UTF-8: a job script
/// could not pass it on faithfully).
pub fn arguments() -> Result<Vec<String>, CliError> {
    std::env::args_os()
        .map(|a| {
            a.into_string().map_err(|a| {
                CliError::input(format!(
                    "the argument {} is not UTF-8 text (allowed with --slurm: UTF-8 arguments, \
                     which the job script passes on)",
                    a.to_string_lossy()
                ))
            })
        })
        .collect()
}

/// This program and the working directory, for a job script.
pub fn program_and_cwd() -> Result<(PathBuf, PathBuf), CliError> {
    let exe = std::env::current_exe()
        .map_err(|e| CliError::internal(format!("cannot find this program: {e}")))?;
    let cwd = std::env::current_dir()
        .map_err(|e| CliError::internal(format!("no working directory: {e}")))?;
    Ok((exe, cwd))
}

/// Write `script` to `dir/job.sbatch` and submit it; the job id (also in `dir/job.id`). A
/// job Slurm rejects is refused (exit 2) and its directory removed.
pub fn sbatch(dir: &Path, script: &str) -> Result<String, CliError> {
    let sbatch = dir.join("job.sbatch");
    std::fs::write(&sbatch, script)
        .map_err(|e| CliError::internal(format!("cannot write {}: {e}", sbatch.display())))?;
    let job = match run_tool(
        Command::new("sbatch").arg("--parsable").arg(&sbatch),
        "sbatch",
    ) {
        Ok(j) => j,
        Err(e) => {
            let _ = std::fs::remove_dir_all(dir);
            return Err(CliError::input(format!(
                "Slurm refused the job: {} (nothing submitted)",
                e.message
            )));
        }
    };
    let job = job.trim().split(';').next().unwrap_or("").to_string();
    if job.is_empty() {
        return Err(CliError::internal("sbatch printed no job id"));
    }
    let _ = std::fs::write(dir.join("job.id"), format!("{job}\n"));
    Ok(job)
}

/// Wait until nothing of `job` is pending, running or completing: `squeue` every 0.5 s at
/// first, then less often (up to every 30 s: a long job does not load the controller); a
/// failing `squeue` is retried, five failures in a row end the wait.
pub fn wait_for(job: &str) -> Result<(), CliError> {
    let mut every = Duration::from_millis(500);
    let mut failures = 0;
    loop {
        match run_tool(
            Command::new("squeue").args(["-h", "-j", job, "-o", "%i %T"]),
            "squeue",
        ) {
            Ok(q) if q.trim().is_empty() => return Ok(()),
            Ok(_) => failures = 0,
            Err(e) => {
                failures += 1;
                if failures >= 5 {
                    return Err(CliError::internal(format!(
                        "{} (five times in a row; the job {job} may still run: see `squeue -j \
                         {job}`)",
                        e.message
                    )));
                }
            }
        }
        std::thread::sleep(every);
        every = (every * 3 / 2).min(Duration::from_secs(30));
    }
}

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
    /// The job script's first lines: the shell, the job's name, `lines` (its shape), the
    /// time limit, the log `log`, the working directory `cwd`, the partition.
    pub fn script_head(&self, name: &str, lines: &[String], log: &Path, cwd: &Path) -> String {
        let mut script = format!("#!/bin/bash\n#SBATCH --job-name=sandjumper-{name}\n");
        for l in lines {
            script += &format!("#SBATCH {l}\n");
        }
        script += &format!("#SBATCH --time={}\n", self.slurm_time);
        // Quoted (Slurm reads quotes in directives); a `%` of the path itself doubled (Slurm
        // expands `%a`, `%j`... in --output), the file name's own patterns kept.
        let dir = log.parent().map_or(String::new(), |d| {
            format!("{}/", d.display()).replace('%', "%%")
        });
        let file = log
            .file_name()
            .map_or(String::new(), |f| f.to_string_lossy().into_owned());
        script += &format!("#SBATCH --output=\"{dir}{file}\"\n");
        script += &format!("#SBATCH --chdir=\"{}\"\n", cwd.display());
        if let Some(p) = &self.slurm_partition {
            script += &format!("#SBATCH --partition={p}\n");
        }
        script + "set -euo pipefail\n"
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
    tool("sbatch", "--slurm")?;
    let dir = fresh_job_dir(out)?;
    let (exe, cwd) = program_and_cwd()?;
    let argv = arguments()?;
    let args = passed_on(
        &argv,
        command,
        &["--out", "--ranks", "--slurm-partition", "--slurm-time"],
        &["--slurm", "--slurm-no-wait"],
    );
    let out_abs = std::path::absolute(out)
        .map_err(|e| CliError::internal(format!("{}: {e}", out.display())))?;
    let mut script = s.queue.script_head(
        name,
        &[format!("--ntasks={tasks}")],
        &dir.join("logs").join("job.out"),
        &cwd,
    );
    script += &format!(
        "exec {} {} {} --ranks \"${{SLURM_NTASKS:-{tasks}}}\" --out {}\n",
        quote(&exe.to_string_lossy()),
        command.join(" "),
        args.iter().map(|a| quote(a)).collect::<Vec<_>>().join(" "),
        quote(&out_abs.to_string_lossy())
    );
    let job = sbatch(&dir, &script)?;
    eprintln!(
        "submitted Slurm job {job} ({tasks} task(s)); script and log in {}",
        dir.display()
    );
    if s.queue.slurm_no_wait {
        println!("{job}");
        eprintln!("when it is done its output is in {}", out.display());
        return Ok(());
    }
    wait_for(&job)?;
    let complete = expect.iter().all(|f| out.join(f).is_file());
    if let Some((st, code)) = unsuccessful(&job, None, complete) {
        let log = dir.join("logs").join("job.out");
        return Err(CliError::internal(format!(
            "Slurm job {job}: {st}, exit code {code}, output {}; log {}:\n    {}",
            if complete { "written" } else { "missing" },
            log.display(),
            log_tail(&log, 8)
        )));
    }
    eprintln!("Slurm job {job} done: {}", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_job_gets_the_commands_arguments_without_the_ones_it_sets() {
        let argv: Vec<String> = [
            "sandjumper",
            "dem",
            "lammps",
            "--preset",
            "small",
            "--out",
            "x",
            "--slurm",
            "--ranks=4",
            "--speed",
            "0.1",
            "--slurm-time",
            "5",
            "--slurm-no-wait",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        assert_eq!(
            passed_on(
                &argv,
                &["dem", "lammps"],
                &["--out", "--ranks", "--slurm-time"],
                &["--slurm", "--slurm-no-wait"]
            ),
            ["--preset", "small", "--speed", "0.1"]
        );
        assert_eq!(quote("a'b"), r"'a'\''b'");
        assert_eq!(job_dir(Path::new("/t/run")), Path::new("/t/run.slurm"));
    }
}
