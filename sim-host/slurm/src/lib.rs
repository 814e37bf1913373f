//! `sandjumper-slurm`: Slurm as the commands that submit to it share it. Slurm's own tools
//! (`sbatch`, `squeue`, `scontrol`) and the job script stay external processes.
//!
//! A submission: [`fresh_job_dir`] makes `DIR.slurm` beside the output, a [`JobScript`] (its
//! queue options [`QueueOptions`], its shape, its log and the command it runs) is submitted
//! by [`submit`], and the [`Job`] is waited for ([`Job::wait`]) and checked
//! ([`Job::unsuccessful`], [`log_tail`]).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use sandjumper_output::{Blame, Blamed};

/// Why a submission failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SlurmError {
    /// The caller's input or environment (no Slurm here, a job Slurm refused, a job folder
    /// in the way).
    #[error("{0}")]
    Input(String),
    /// A tool failed after the job was accepted, or the folder could not be written.
    #[error("{0}")]
    Internal(String),
}

impl Blamed for SlurmError {
    fn blame(&self) -> Blame {
        match self {
            Self::Input(_) => Blame::Input,
            Self::Internal(_) => Blame::Internal,
        }
    }
}

/// The queue options of a job: partition, time limit, waiting.
#[derive(Debug, Clone, PartialEq)]
pub struct QueueOptions {
    /// Partition (None: the cluster's default).
    pub partition: Option<String>,
    /// Time limit of the job (of each array task) in Slurm's format, e.g. 30, 1:00:00.
    pub time: String,
    /// Submit and return without waiting.
    pub no_wait: bool,
}

impl Default for QueueOptions {
    fn default() -> Self {
        Self {
            partition: None,
            time: "1:00:00".into(),
            no_wait: false,
        }
    }
}

/// A job script: `#!/bin/bash`, the `#SBATCH` lines, `set -euo pipefail`, one command.
#[derive(Debug, Clone, PartialEq)]
pub struct JobScript {
    /// The job's name after `sandjumper-`.
    pub name: String,
    /// Its shape, as `#SBATCH` options (`--array=1-4`, `--ntasks=2`, ...).
    pub shape: Vec<String>,
    /// Its log (`%a`, `%j` patterns in the file name are Slurm's).
    pub log: PathBuf,
    /// Its working directory.
    pub cwd: PathBuf,
    /// Partition and time limit.
    pub queue: QueueOptions,
    /// The command line it runs (shell text, already quoted).
    pub command: String,
}

impl JobScript {
    /// The script's text.
    pub fn text(&self) -> String {
        let mut script = format!("#!/bin/bash\n#SBATCH --job-name=sandjumper-{}\n", self.name);
        for l in &self.shape {
            script += &format!("#SBATCH {l}\n");
        }
        script += &format!("#SBATCH --time={}\n", self.queue.time);
        // Quoted (Slurm reads quotes in directives); a `%` of the path itself doubled (Slurm
        // expands `%a`, `%j`... in --output), the file name's own patterns kept.
        let dir = self.log.parent().map_or(String::new(), |d| {
            format!("{}/", d.display()).replace('%', "%%")
        });
        let file = self
            .log
            .file_name()
            .map_or(String::new(), |f| f.to_string_lossy().into_owned());
        script += &format!("#SBATCH --output=\"{dir}{file}\"\n");
        script += &format!("#SBATCH --chdir=\"{}\"\n", self.cwd.display());
        if let Some(p) = &self.queue.partition {
            script += &format!("#SBATCH --partition={p}\n");
        }
        script + "set -euo pipefail\n" + &self.command
    }
}

/// A submitted job: its id and its folder (`job.sbatch`, `job.id`, `logs/`).
#[derive(Debug, Clone, PartialEq)]
pub struct Job {
    /// Slurm's job id.
    pub id: String,
    /// The job's folder.
    pub dir: PathBuf,
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
pub fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// A command's own arguments (after the words `after`, e.g. `["dem", "lammps"]`) without
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

/// Refuse without Slurm's `name` on PATH (`option` names what needs it).
pub fn tool(name: &str, option: &str) -> Result<(), SlurmError> {
    match Command::new(name).arg("--version").output() {
        Ok(o) if o.status.success() => Ok(()),
        _ => Err(SlurmError::Input(format!(
            "{option} needs Slurm's `{name}` on PATH (not found or not working here); run on a \
             cluster's login node, or without {option}"
        ))),
    }
}

/// Run a Slurm tool; its stdout, or what it said when it failed.
pub fn run_tool(cmd: &mut Command, what: &str) -> Result<String, SlurmError> {
    let o = cmd
        .output()
        .map_err(|e| SlurmError::Internal(format!("cannot run {what}: {e}")))?;
    if !o.status.success() {
        return Err(SlurmError::Internal(format!(
            "{what} failed ({}): {}",
            o.status,
            String::from_utf8_lossy(&o.stderr).trim()
        )));
    }
    Ok(String::from_utf8_lossy(&o.stdout).into_owned())
}

impl Job {
    /// The job's (or with `task`, an array task's) final state and exit code, from `scontrol
    /// show job` (for a task, the record whose `ArrayTaskId` is it); None when Slurm has none
    /// (cancelled before it started, or forgotten after `MinJobAge`).
    pub fn state(&self, task: Option<u32>) -> Option<(String, String)> {
        let id = match task {
            Some(t) => format!("{}_{t}", self.id),
            None => self.id.clone(),
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

    /// How the job (or, with `task`, an array task) ended when it did not succeed: its state
    /// and exit code; None when it succeeded and its output is `written`.
    pub fn unsuccessful(&self, task: Option<u32>, written: bool) -> Option<(String, String)> {
        let state = self.state(task);
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

    /// Wait until nothing of the job is pending, running or completing: `squeue` every 0.5 s
    /// at first, then less often (up to every 30 s); a failing `squeue` is retried, five
    /// failures in a row end the wait.
    pub fn wait(&self) -> Result<(), SlurmError> {
        let job = &self.id;
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
                        return Err(SlurmError::Internal(format!(
                            "{e} (five times in a row; the job {job} may still run: see `squeue -j \
                             {job}`)"
                        )));
                    }
                }
            }
            std::thread::sleep(every);
            every = (every * 3 / 2).min(Duration::from_secs(30));
        }
    }
}

/// The last `n` lines of a log, indented for a message.
pub fn log_tail(path: &Path, n: usize) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n    ")
}

/// Make `DIR.slurm` (with `logs/`) for `out`, replacing an earlier job directory of ours
/// unless its job (`job.id`) is still queued or running; its canonical path.
pub fn fresh_job_dir(out: &Path) -> Result<PathBuf, SlurmError> {
    let dir = job_dir(out);
    if dir.exists() {
        if !dir.join("job.sbatch").is_file() {
            return Err(SlurmError::Input(format!(
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
                return Err(SlurmError::Input(format!(
                    "{}: its job {id} is still queued or running, or Slurm cannot say (allowed: a \
                     job directory whose job has ended; wait for it, or `scancel {id}`)",
                    dir.display()
                )));
            }
        }
        std::fs::remove_dir_all(&dir)
            .map_err(|e| SlurmError::Internal(format!("cannot clear {}: {e}", dir.display())))?;
    }
    std::fs::create_dir_all(dir.join("logs"))
        .map_err(|e| SlurmError::Input(format!("cannot create {}: {e}", dir.display())))?;
    std::fs::canonicalize(&dir).map_err(|e| SlurmError::Internal(format!("{}: {e}", dir.display())))
}

/// This program's arguments as text (an error naming one that is not UTF-8: a job script
/// could not pass it on faithfully).
pub fn arguments() -> Result<Vec<String>, SlurmError> {
    std::env::args_os()
        .map(|a| {
            a.into_string().map_err(|a| {
                SlurmError::Input(format!(
                    "the argument {} is not UTF-8 text (allowed with --slurm: UTF-8 arguments, \
                     which the job script passes on)",
                    a.to_string_lossy()
                ))
            })
        })
        .collect()
}

/// This program and the working directory, for a job script.
pub fn program_and_cwd() -> Result<(PathBuf, PathBuf), SlurmError> {
    let exe = std::env::current_exe()
        .map_err(|e| SlurmError::Internal(format!("cannot find this program: {e}")))?;
    let cwd = std::env::current_dir()
        .map_err(|e| SlurmError::Internal(format!("no working directory: {e}")))?;
    Ok((exe, cwd))
}

/// Write `script` to `dir/job.sbatch` and submit it; the job (its id also in `dir/job.id`).
/// A job Slurm rejects is refused (input) and its directory removed.
pub fn submit(dir: &Path, script: &JobScript) -> Result<Job, SlurmError> {
    let sbatch = dir.join("job.sbatch");
    std::fs::write(&sbatch, script.text())
        .map_err(|e| SlurmError::Internal(format!("cannot write {}: {e}", sbatch.display())))?;
    let job = match run_tool(
        Command::new("sbatch").arg("--parsable").arg(&sbatch),
        "sbatch",
    ) {
        Ok(j) => j,
        Err(e) => {
            let _ = std::fs::remove_dir_all(dir);
            return Err(SlurmError::Input(format!(
                "Slurm refused the job: {e} (nothing submitted)"
            )));
        }
    };
    let id = job.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() {
        return Err(SlurmError::Internal("sbatch printed no job id".into()));
    }
    let _ = std::fs::write(dir.join("job.id"), format!("{id}\n"));
    Ok(Job {
        id,
        dir: dir.to_path_buf(),
    })
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
            shard_task_arguments(&argv, &["sweep"]),
            ["--kind", "single", "--freq", "8:12:1", "--phi", "0.57"]
        );
    }

    #[test]
    fn a_script_quotes_its_log_folder_and_keeps_the_file_names_patterns() {
        let s = JobScript {
            name: "sweep".into(),
            shape: vec!["--array=1-3".into()],
            log: "/j/100%.slurm/logs/task-%a.out".into(),
            cwd: "/w".into(),
            queue: QueueOptions {
                partition: Some("debug".into()),
                ..QueueOptions::default()
            },
            command: "exec true\n".into(),
        };
        assert_eq!(
            s.text(),
            "#!/bin/bash\n#SBATCH --job-name=sandjumper-sweep\n#SBATCH --array=1-3\n\
             #SBATCH --time=1:00:00\n#SBATCH --output=\"/j/100%%.slurm/logs/task-%a.out\"\n\
             #SBATCH --chdir=\"/w\"\n#SBATCH --partition=debug\nset -euo pipefail\nexec true\n"
        );
    }
}

/// One job that runs this very program's command again on the cluster: the words
/// [`CommandJob::command`] (e.g. `["dem", "lammps"]`), this process's own arguments without
/// the Slurm options, `--out` and `--ranks`, then `--ranks` and `--out`.
#[derive(Debug, Clone)]
pub struct CommandJob<'a> {
    /// The job's name in the queue.
    pub name: &'a str,
    /// The command's words.
    pub command: &'a [&'a str],
    /// Tasks (MPI ranks) of the job.
    pub tasks: u32,
    /// The output folder the job writes.
    pub out: &'a Path,
    /// Files the job must have written into `out` for it to count as done.
    pub expect: &'a [&'a str],
    /// Partition, time limit, waiting.
    pub queue: QueueOptions,
}

/// What a submitted [`CommandJob`] came to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CommandJobOutcome {
    /// Submitted without waiting ([`QueueOptions::no_wait`]): the job's id.
    Queued {
        /// Slurm's job id.
        id: String,
    },
    /// The job ran and wrote what was expected.
    Done {
        /// Slurm's job id.
        id: String,
    },
}

/// Submit `job` (see [`CommandJob`]), wait for it unless told not to, and check that it
/// succeeded and wrote every expected file. A job that failed, timed out or was cancelled is
/// an internal error with the tail of its log. Where the job's script and log are, and when
/// it is done, are `progress` notes.
pub fn submit_command(
    job: &CommandJob,
    progress: &dyn sandjumper_output::Progress,
) -> Result<CommandJobOutcome, SlurmError> {
    tool("sbatch", "--slurm")?;
    let dir = fresh_job_dir(job.out)?;
    let (exe, cwd) = program_and_cwd()?;
    let argv = arguments()?;
    let args = passed_on(
        &argv,
        job.command,
        &["--out", "--ranks", "--slurm-partition", "--slurm-time"],
        &["--slurm", "--slurm-no-wait"],
    );
    let out_abs = std::path::absolute(job.out)
        .map_err(|e| SlurmError::Internal(format!("{}: {e}", job.out.display())))?;
    let tasks = job.tasks;
    let script = JobScript {
        name: job.name.to_string(),
        shape: vec![format!("--ntasks={tasks}")],
        log: dir.join("logs").join("job.out"),
        cwd,
        queue: job.queue.clone(),
        command: format!(
            "exec {} {} {} --ranks \"${{SLURM_NTASKS:-{tasks}}}\" --out {}\n",
            quote(&exe.to_string_lossy()),
            job.command.join(" "),
            args.iter().map(|a| quote(a)).collect::<Vec<_>>().join(" "),
            quote(&out_abs.to_string_lossy())
        ),
    };
    let submitted = submit(&dir, &script)?;
    progress.note(&format!(
        "submitted Slurm job {} ({tasks} task(s)); script and log in {}",
        submitted.id,
        dir.display()
    ));
    if job.queue.no_wait {
        return Ok(CommandJobOutcome::Queued { id: submitted.id });
    }
    submitted.wait()?;
    let complete = job.expect.iter().all(|f| job.out.join(f).is_file());
    if let Some((st, code)) = submitted.unsuccessful(None, complete) {
        let log = dir.join("logs").join("job.out");
        return Err(SlurmError::Internal(format!(
            "Slurm job {}: {st}, exit code {code}, output {}; log {}:\n    {}",
            submitted.id,
            if complete { "written" } else { "missing" },
            log.display(),
            log_tail(&log, 8)
        )));
    }
    progress.note(&format!(
        "Slurm job {} done: {}",
        submitted.id,
        job.out.display()
    ));
    Ok(CommandJobOutcome::Done { id: submitted.id })
}

/// A command run as a Slurm job array of shards: task `I` of [`ShardedJob::tasks`] runs this
/// very program's command again (the words [`ShardedJob::command`], then this process's own
/// arguments without the Slurm options, `--out`, `--shard` and `--threads`) with `--shard
/// I/N --threads CPUS --out DIR.slurm/shard-I`; each task's log is `DIR.slurm/logs/task-I.out`.
#[derive(Debug, Clone)]
pub struct ShardedJob<'a> {
    /// The job's name in the queue.
    pub name: &'a str,
    /// The command's words (e.g. `["sweep"]`).
    pub command: &'a [&'a str],
    /// Array tasks, one shard each.
    pub tasks: u32,
    /// CPUs of each task (its `--threads`).
    pub cpus: u32,
    /// The output folder the shards are merged into (the job's folder is `DIR.slurm` beside it).
    pub out: &'a Path,
    /// The file a task must have written into its shard folder for it to count as done.
    pub expect: &'a str,
    /// Partition, time limit, waiting.
    pub queue: QueueOptions,
}

/// What a submitted [`ShardedJob`] came to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ShardedJobOutcome {
    /// Submitted without waiting ([`QueueOptions::no_wait`]).
    Queued {
        /// Slurm's job id.
        id: String,
        /// The job's folder (`DIR.slurm`), where the shards will be.
        dir: PathBuf,
    },
    /// Every task succeeded.
    Done {
        /// Slurm's job id.
        id: String,
        /// The shard folders, in task order.
        shards: Vec<PathBuf>,
    },
}

/// The command's own arguments in `argv` (after the words `command`) without the ones each
/// task of a [`ShardedJob`] sets itself: `--out`, `--shard`, `--threads` and every `--slurm*`.
pub fn shard_task_arguments(argv: &[String], command: &[&str]) -> Vec<String> {
    passed_on(
        argv,
        command,
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

/// Submit `job` as a job array (see [`ShardedJob`]); unless told not to, wait for it and check
/// every task: its shard folder complete, its final state and exit code. A task that failed,
/// was cancelled or timed out is an internal error with the tail of its log. Where the job's
/// script and logs are is a `progress` note.
pub fn submit_sharded(
    job: &ShardedJob,
    progress: &dyn sandjumper_output::Progress,
) -> Result<ShardedJobOutcome, SlurmError> {
    let argv = arguments()?;
    let tasks = job.tasks;
    tool("sbatch", "--slurm")?;
    let dir = fresh_job_dir(job.out)?;
    let (exe, cwd) = program_and_cwd()?;
    let script = JobScript {
        name: job.name.to_string(),
        shape: vec![
            format!("--array=1-{tasks}"),
            format!("--cpus-per-task={}", job.cpus),
        ],
        log: dir.join("logs").join("task-%a.out"),
        cwd,
        queue: job.queue.clone(),
        command: format!(
            "exec {} {} {} --shard \"$SLURM_ARRAY_TASK_ID/{tasks}\" --threads \
             \"${{SLURM_CPUS_PER_TASK:-1}}\" --out {}/shard-\"$SLURM_ARRAY_TASK_ID\"\n",
            quote(&exe.to_string_lossy()),
            job.command.join(" "),
            shard_task_arguments(&argv, job.command)
                .iter()
                .map(|a| quote(a))
                .collect::<Vec<_>>()
                .join(" "),
            quote(&dir.to_string_lossy())
        ),
    };
    let submitted = submit(&dir, &script)?;
    progress.note(&format!(
        "submitted Slurm job {} (array 1-{tasks}, {} CPU(s) each); script and logs in {}",
        submitted.id,
        job.cpus,
        dir.display()
    ));
    if job.queue.no_wait {
        return Ok(ShardedJobOutcome::Queued {
            id: submitted.id,
            dir,
        });
    }
    submitted.wait()?;
    let shards: Vec<PathBuf> = (1..=tasks)
        .map(|i| dir.join(format!("shard-{i}")))
        .collect();
    let mut failed = Vec::new();
    for (i, shard) in (1..=tasks).zip(&shards) {
        let complete = shard.join(job.expect).is_file();
        if let Some((st, code)) = submitted.unsuccessful(Some(i), complete) {
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
        return Err(SlurmError::Internal(format!(
            "Slurm job {}: {} of {tasks} task(s) did not succeed; nothing merged (fix and \
             resubmit, or merge the good shards by hand)\n{}",
            submitted.id,
            failed.len(),
            failed.join("\n")
        )));
    }
    Ok(ShardedJobOutcome::Done {
        id: submitted.id,
        shards,
    })
}
