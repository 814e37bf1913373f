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
    /// Nodes to spread the job's tasks over (None: as Slurm places them).
    pub nodes: Option<u32>,
    /// Submit and return without waiting.
    pub no_wait: bool,
}

impl Default for QueueOptions {
    fn default() -> Self {
        Self {
            partition: None,
            time: "1:00:00".into(),
            nodes: None,
            no_wait: false,
        }
    }
}

impl QueueOptions {
    /// The time limit in minutes, from Slurm's forms: `M`, `M:S`, `H:M:S`, `D-H`, `D-H:M`,
    /// `D-H:M:S`. `None` for a form it does not take (or `UNLIMITED`).
    pub fn time_limit_min(&self) -> Option<f64> {
        let t = self.time.trim();
        let (days, rest) = match t.split_once('-') {
            Some((d, r)) => (d.parse::<f64>().ok()?, Some(r)),
            None => (0.0, None),
        };
        let num = |w: &str| w.parse::<f64>().ok().filter(|v| *v >= 0.0);
        let parts: Vec<&str> = rest.unwrap_or(t).split(':').collect();
        let minutes = match (rest.is_some(), parts.as_slice()) {
            (false, [m]) => num(m)?,
            (false, [m, s]) => num(m)? + num(s)? / 60.0,
            (_, [h, m, s]) => 60.0 * num(h)? + num(m)? + num(s)? / 60.0,
            (true, [h]) => 60.0 * num(h)?,
            (true, [h, m]) => 60.0 * num(h)? + num(m)?,
            _ => return None,
        };
        Some(24.0 * 60.0 * days + minutes)
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
        if let Some(n) = self.queue.nodes {
            script += &format!("#SBATCH --nodes={n}\n");
        }
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
    /// failures in a row end the wait. When `progress`'s caller asks to stop (Ctrl-C), the
    /// wait ends within [`STOP_CHECK`] with an error naming the job, which runs on.
    pub fn wait(&self, progress: &dyn sandjumper_output::Progress) -> Result<(), SlurmError> {
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
            let until = std::time::Instant::now() + every;
            while std::time::Instant::now() < until {
                if progress.cancelled() {
                    return Err(SlurmError::Internal(format!(
                        "stopped waiting for Slurm job {job}: it runs on (`squeue -j {job}`; \
                         `scancel {job}` ends it); its script, logs and outputs are in {}",
                        self.dir.display()
                    )));
                }
                std::thread::sleep(
                    STOP_CHECK.min(until.saturating_duration_since(std::time::Instant::now())),
                );
            }
            every = (every * 3 / 2).min(Duration::from_secs(30));
        }
    }
}

/// How often a wait for a job looks at whether its caller asked to stop.
pub const STOP_CHECK: Duration = Duration::from_millis(200);

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

/// The working directory a job starts in: this process's (relative paths in a job's
/// arguments mean what they mean here).
pub fn working_dir() -> Result<PathBuf, SlurmError> {
    std::env::current_dir().map_err(|e| SlurmError::Internal(format!("no working directory: {e}")))
}

/// `path` as text for a job script, or refused (input) when it is not UTF-8 text: a job script
/// could not pass it on faithfully. `what` names it in the message (`the program`,
/// `--trajectory`, ...).
pub fn path_text<'a>(path: &'a Path, what: &str) -> Result<&'a str, SlurmError> {
    path.to_str().ok_or_else(|| {
        SlurmError::Input(format!(
            "{what} {} is not UTF-8 text (allowed with --slurm: UTF-8 paths, which the job \
             script passes on)",
            path.display()
        ))
    })
}

/// A job script's command: `program` and `args`, each word quoted; a program path that is not
/// UTF-8 text is refused ([`path_text`]).
pub fn command_line(program: &Path, args: &[String]) -> Result<String, SlurmError> {
    let program = path_text(program, "the program")?;
    Ok(std::iter::once(program)
        .chain(args.iter().map(String::as_str))
        .map(quote)
        .collect::<Vec<_>>()
        .join(" "))
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

/// One job that runs a command of `program` (the `sandjumper` binary, on the cluster's shared
/// file system) on the cluster: `program ARGS --ranks TASKS --out OUT`.
#[derive(Debug, Clone)]
pub struct CommandJob<'a> {
    /// The job's name in the queue.
    pub name: &'a str,
    /// The program the job runs.
    pub program: &'a Path,
    /// Its words (the command and its options, e.g. `dem lammps --preset small`), without
    /// `--ranks` and `--out`, which the job adds.
    pub args: &'a [String],
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

impl CommandJob<'_> {
    /// The job's script (its folder `dir`, started in `cwd`).
    pub fn script(&self, dir: &Path, cwd: &Path) -> Result<JobScript, SlurmError> {
        let out_abs = std::path::absolute(self.out)
            .map_err(|e| SlurmError::Internal(format!("{}: {e}", self.out.display())))?;
        let out = path_text(&out_abs, "the output folder")?;
        let tasks = self.tasks;
        Ok(JobScript {
            name: self.name.to_string(),
            shape: vec![format!("--ntasks={tasks}")],
            log: dir.join("logs").join("job.out"),
            cwd: cwd.to_path_buf(),
            queue: self.queue.clone(),
            command: format!(
                "exec {} --ranks \"${{SLURM_NTASKS:-{tasks}}}\" --out {}\n",
                command_line(self.program, self.args)?,
                quote(out)
            ),
        })
    }
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
    let cwd = working_dir()?;
    let dir = fresh_job_dir(job.out)?;
    let script = job.script(&dir, &cwd).inspect_err(|_| {
        let _ = std::fs::remove_dir_all(&dir);
    })?;
    let submitted = submit(&dir, &script)?;
    progress.note(&format!(
        "submitted Slurm job {} ({} task(s)); script and log in {}",
        submitted.id,
        job.tasks,
        dir.display()
    ));
    if job.queue.no_wait {
        return Ok(CommandJobOutcome::Queued { id: submitted.id });
    }
    submitted.wait(progress)?;
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

/// A command run as a Slurm job array of shards: task `I` of [`ShardedJob::tasks`] runs
/// `program ARGS --shard I/N --threads CPUS --out DIR.slurm/shard-I`; each task's log is
/// `DIR.slurm/logs/task-I.out`.
#[derive(Debug, Clone)]
pub struct ShardedJob<'a> {
    /// The job's name in the queue.
    pub name: &'a str,
    /// The program each task runs (the `sandjumper` binary, on the cluster's shared file
    /// system).
    pub program: &'a Path,
    /// Its words (the command and its options, e.g. `sweep --kind single --freq 8:12:1`),
    /// without `--shard`, `--threads` and `--out`, which each task adds.
    pub args: &'a [String],
    /// Files written into the job's folder before it is submitted, name and text (e.g. the
    /// parameter file its tasks read: the words may name it in
    /// `absolute(job_dir(out))/NAME`).
    pub files: &'a [(&'a str, String)],
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

impl ShardedJob<'_> {
    /// The job array's script (its folder `dir`, started in `cwd`).
    pub fn script(&self, dir: &Path, cwd: &Path) -> Result<JobScript, SlurmError> {
        let tasks = self.tasks;
        let dir_text = path_text(dir, "the job's folder")?;
        Ok(JobScript {
            name: self.name.to_string(),
            shape: vec![
                format!("--array=1-{tasks}"),
                format!("--cpus-per-task={}", self.cpus),
            ],
            log: dir.join("logs").join("task-%a.out"),
            cwd: cwd.to_path_buf(),
            queue: self.queue.clone(),
            command: format!(
                "exec {} --shard \"$SLURM_ARRAY_TASK_ID/{tasks}\" --threads \
                 \"${{SLURM_CPUS_PER_TASK:-1}}\" --out {}/shard-\"$SLURM_ARRAY_TASK_ID\"\n",
                command_line(self.program, self.args)?,
                quote(dir_text)
            ),
        })
    }
}

/// Submit `job` as a job array (see [`ShardedJob`]); unless told not to, wait for it and check
/// every task: its shard folder complete, its final state and exit code. A task that failed,
/// was cancelled or timed out is an internal error with the tail of its log. Where the job's
/// script and logs are is a `progress` note.
pub fn submit_sharded(
    job: &ShardedJob,
    progress: &dyn sandjumper_output::Progress,
) -> Result<ShardedJobOutcome, SlurmError> {
    let tasks = job.tasks;
    tool("sbatch", "--slurm")?;
    let cwd = working_dir()?;
    let dir = fresh_job_dir(job.out)?;
    let script = job.script(&dir, &cwd).inspect_err(|_| {
        let _ = std::fs::remove_dir_all(&dir);
    })?;
    for (name, text) in job.files {
        let path = dir.join(name);
        if let Err(e) = std::fs::write(&path, text) {
            let _ = std::fs::remove_dir_all(&dir);
            return Err(SlurmError::Internal(format!(
                "cannot write {}: {e}",
                path.display()
            )));
        }
    }
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
    submitted.wait(progress)?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_limits_read_in_every_form_slurm_takes() {
        let limit = |t: &str| {
            QueueOptions {
                time: t.into(),
                ..QueueOptions::default()
            }
            .time_limit_min()
        };
        assert_eq!(limit("30"), Some(30.0));
        assert_eq!(limit("1:30"), Some(1.5));
        assert_eq!(limit("2:00:00"), Some(120.0));
        assert_eq!(limit("1-2"), Some(1560.0));
        assert_eq!(limit("1-0:30"), Some(1470.0));
        assert_eq!(limit("1-0:0:30"), Some(1440.5));
        assert_eq!(limit("UNLIMITED"), None);
        assert_eq!(limit("1:2:3:4"), None);
    }

    fn words(w: &[&str]) -> Vec<String> {
        w.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn a_job_runs_the_program_given_with_the_words_given_then_ranks_and_out() {
        let args = words(&[
            "dem",
            "lammps",
            "--preset",
            "small",
            "--trajectory",
            "it's.csv",
        ]);
        let job = CommandJob {
            name: "dem-lammps",
            program: Path::new("/opt/bin/sandjumper"),
            args: &args,
            tasks: 4,
            out: Path::new("/t/run"),
            expect: &["summary.json"],
            queue: QueueOptions::default(),
        };
        let script = job
            .script(Path::new("/t/run.slurm"), Path::new("/w"))
            .unwrap();
        assert_eq!(
            script.command,
            "exec '/opt/bin/sandjumper' 'dem' 'lammps' '--preset' 'small' '--trajectory' \
             'it'\\''s.csv' --ranks \"${SLURM_NTASKS:-4}\" --out '/t/run'\n"
        );
        assert_eq!(script.shape, ["--ntasks=4"]);
        assert_eq!(quote("a'b"), r"'a'\''b'");
        assert_eq!(job_dir(Path::new("/t/run")), Path::new("/t/run.slurm"));
    }

    #[test]
    fn each_task_runs_the_words_given_then_its_shard_threads_and_folder() {
        let args = words(&["sweep", "--kind", "single", "--freq", "8:12:1"]);
        let job = ShardedJob {
            name: "sweep",
            program: Path::new("/b/sandjumper"),
            args: &args,
            files: &[],
            tasks: 3,
            cpus: 2,
            out: Path::new("/t/sw"),
            expect: "sweep.toml",
            queue: QueueOptions::default(),
        };
        let script = job
            .script(Path::new("/t/sw.slurm"), Path::new("/w"))
            .unwrap();
        assert_eq!(
            script.command,
            "exec '/b/sandjumper' 'sweep' '--kind' 'single' '--freq' '8:12:1' --shard \
             \"$SLURM_ARRAY_TASK_ID/3\" --threads \"${SLURM_CPUS_PER_TASK:-1}\" --out \
             '/t/sw.slurm'/shard-\"$SLURM_ARRAY_TASK_ID\"\n"
        );
        assert_eq!(script.shape, ["--array=1-3", "--cpus-per-task=2"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_program_or_argument_that_is_not_text_is_refused() {
        use std::os::unix::ffi::OsStrExt;
        let program = Path::new(std::ffi::OsStr::from_bytes(b"/b/sand\xffjumper"));
        let e = command_line(program, &[]).unwrap_err();
        assert!(
            matches!(e, SlurmError::Input(ref m) if m.contains("not UTF-8")),
            "{e}"
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
        // Nodes asked for, after the time limit.
        let spread = JobScript {
            queue: QueueOptions {
                nodes: Some(4),
                ..s.queue.clone()
            },
            ..s
        };
        assert!(
            spread
                .text()
                .contains("#SBATCH --time=1:00:00\n#SBATCH --nodes=4\n")
        );
    }
}
