//! A sweep on a Slurm cluster: a job array of shards, one per task, each running the
//! `sandjumper` binary's `sweep` on its shard ([`sandjumper_slurm::submit_sharded`]), waited
//! for and merged into the output folder ([`merge()`]).

use std::path::{Path, PathBuf};

use sandjumper_model::trajectory::kind_name;
use sandjumper_output::Progress;
use sandjumper_slurm::{QueueOptions, ShardedJob, ShardedJobOutcome, SlurmError};

use super::{
    MergeOutcome, MergeRequest, SweepDrive, SweepRequest, SweepSpec, ValueRange, WrittenSweep,
    merge,
};
use crate::StudyError;

/// The parameter file a Slurm sweep's tasks read, in the job's folder (`OUT.slurm/`).
pub const JOB_PARAMS_FILE: &str = "params.toml";

/// Most tasks of a Slurm sweep's job array ([`SlurmSweepRequest::tasks`]).
pub const MAX_TASKS: u32 = 10_000;

/// Most CPUs of each task ([`SlurmSweepRequest::cpus_per_task`]).
pub const MAX_CPUS_PER_TASK: u32 = 1024;

/// A sweep run on a Slurm cluster as a job array.
#[derive(Debug, Clone, PartialEq)]
pub struct SlurmSweepRequest {
    /// The sweep. Its `shard` must be `None` (each task runs one); its `threads` are not used
    /// (each task has [`SlurmSweepRequest::cpus_per_task`]).
    pub sweep: SweepRequest,
    /// Array tasks, one shard each.
    pub tasks: u32,
    /// CPUs of each task (its sweep's threads).
    pub cpus_per_task: u32,
    /// Partition, time limit, waiting.
    pub queue: QueueOptions,
    /// The `sandjumper` binary the tasks run (on the cluster's shared file system).
    pub program: PathBuf,
    /// The output folder the shards are merged into (the job's folder is `OUT.slurm` beside it).
    pub out: PathBuf,
}

/// What a Slurm sweep came to.
#[derive(Debug)]
pub enum SlurmSweepOutcome {
    /// Submitted without waiting: merge the shards later (`sandjumper merge DIR/shard-* --out
    /// OUT`).
    Queued {
        /// Slurm's job id.
        id: String,
        /// The job's folder (`OUT.slurm`), where the shards will be.
        dir: PathBuf,
    },
    /// Every task succeeded and the shards were merged into the output folder.
    Merged {
        /// Slurm's job id.
        id: String,
        /// The merged sweep.
        merged: Box<MergeOutcome>,
        /// The folder written.
        written: WrittenSweep,
    },
}

impl From<SlurmError> for StudyError {
    fn from(e: SlurmError) -> Self {
        match e {
            SlurmError::Input(m) => Self::Input(m),
            SlurmError::Internal(m) => Self::Internal(m),
        }
    }
}

impl SweepRequest {
    /// The words of `sandjumper sweep` that ask for this sweep's combinations, without
    /// `--shard`, `--threads` and `--out` (each Slurm task adds them): every axis, the
    /// tolerance, the drive, and `--params params` if the request has overrides. An axis that
    /// is no range `A:B:STEP` is refused (the command line could not say it).
    pub fn task_arguments(&self, params: Option<&Path>) -> Result<Vec<String>, StudyError> {
        // Every field named: one added later must be carried here too.
        let SweepSpec {
            kinds,
            models,
            phis,
            freqs_hz,
            taus_s,
            rtol,
            drive,
        } = &self.spec;
        if kinds.is_empty() || models.is_empty() {
            return Err(StudyError::input(
                "the sweep has no jump kind or no ground model (allowed: at least one of each)",
            ));
        }
        let kinds: Vec<&str> = kinds.iter().map(|&k| kind_name(k)).collect();
        let models: Vec<&str> = models.iter().map(|m| m.as_str()).collect();
        let mut args: Vec<String> = vec![
            "sweep".into(),
            format!("--kind={}", kinds.join(",")),
            format!("--model={}", models.join(",")),
        ];
        for (flag, values, what) in [
            ("--phi", phis, "packing fractions"),
            ("--freq", freqs_hz, "frequencies"),
            ("--tau", taus_s, "delays"),
        ] {
            if values.is_empty() {
                return Err(StudyError::input(format!(
                    "the sweep has no {what} (allowed: at least one)"
                )));
            }
            let written = ValueRange::written_for(values).ok_or_else(|| {
                StudyError::input(format!(
                    "the sweep's {what} {values:?} are not one range A:B:STEP, which each Slurm \
                     task's {flag} needs (allowed: one value, or evenly spaced ascending values)"
                ))
            })?;
            args.push(format!("{flag}={written}"));
        }
        // `{}` writes the shortest text that reads back as the same f64.
        args.push(format!("--rtol={rtol}"));
        if let Some(p) = params {
            let text = sandjumper_slurm::path_text(p, "the parameter file (beside --out)")?;
            args.push(format!("--params={text}"));
        }
        if let SweepDrive::Sil { gain_lowering } = drive {
            args.push("--link=sil".into());
            if let Some(g) = gain_lowering {
                args.push(format!("--gain-lowering={g}"));
            }
        }
        Ok(args)
    }
}

/// Run the sweep `request` asks for on a Slurm cluster: check it here, submit the job array
/// (the overrides in the job's folder, [`JOB_PARAMS_FILE`]), and unless told not to wait,
/// wait for every task and merge the shards into [`SlurmSweepRequest::out`]. A task that
/// failed is an internal error with its log's tail; nothing is merged then.
pub fn run_on_slurm(
    request: &SlurmSweepRequest,
    progress: &dyn Progress,
) -> Result<SlurmSweepOutcome, StudyError> {
    request.sweep.validate()?;
    if !(1..=MAX_TASKS).contains(&request.tasks) {
        return Err(StudyError::input(format!(
            "--slurm {} not allowed (allowed: 1 to {MAX_TASKS} tasks)",
            request.tasks
        )));
    }
    if !(1..=MAX_CPUS_PER_TASK).contains(&request.cpus_per_task) {
        return Err(StudyError::input(format!(
            "--slurm-cpus {} not allowed (allowed: 1 to {MAX_CPUS_PER_TASK})",
            request.cpus_per_task
        )));
    }
    if request.sweep.shard.is_some() {
        return Err(StudyError::input(
            "--slurm N makes the shards itself (task I runs --shard I/N): drop --shard",
        ));
    }
    let job_dir = std::path::absolute(sandjumper_slurm::job_dir(&request.out))
        .map_err(|e| StudyError::internal(format!("{}: {e}", request.out.display())))?;
    let files: Vec<(&str, String)> = match &request.sweep.params {
        Some(p) => vec![(JOB_PARAMS_FILE, p.text.clone())],
        None => Vec::new(),
    };
    let params_path = job_dir.join(JOB_PARAMS_FILE);
    let args = request
        .sweep
        .task_arguments(request.sweep.params.as_ref().map(|_| params_path.as_path()))?;
    let job = ShardedJob {
        name: "sweep",
        program: &request.program,
        args: &args,
        files: &files,
        tasks: request.tasks,
        cpus: request.cpus_per_task,
        out: &request.out,
        expect: "sweep.toml",
        queue: request.queue.clone(),
    };
    match sandjumper_slurm::submit_sharded(&job, progress)? {
        ShardedJobOutcome::Queued { id, dir } => Ok(SlurmSweepOutcome::Queued { id, dir }),
        ShardedJobOutcome::Done { id, shards } => {
            progress.note(&format!(
                "all {} task(s) of job {id} done; merging",
                shards.len()
            ));
            let merge_request = MergeRequest {
                dirs: shards,
                out: request.out.clone(),
            };
            let mut merged = merge(&merge_request, progress)?;
            // The overrides as the caller named them (the tasks read the job folder's copy),
            // as a sweep run here records them.
            merged.meta.spec.params_file = request
                .sweep
                .params
                .as_ref()
                .map(|p| p.path.display().to_string());
            let written = merged.write(&request.out)?;
            Ok(SlurmSweepOutcome::Merged {
                id,
                merged: Box::new(merged),
                written,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sandjumper_core::trajectory::JumpKind;
    use sandjumper_model::params::ModelName;

    #[test]
    fn a_tasks_words_say_every_axis_the_tolerance_the_drive_and_the_overrides() {
        let request = SweepRequest {
            spec: SweepSpec {
                kinds: vec![JumpKind::Single, JumpKind::DelayedStutter],
                models: vec![ModelName::Eq1Linear, ModelName::Eq4],
                phis: ValueRange::parse("0.57:0.62:0.01").unwrap().values,
                freqs_hz: vec![12.5],
                taus_s: ValueRange::parse("0:0.1:0.05").unwrap().values,
                rtol: 1e-9,
                drive: SweepDrive::Sil {
                    gain_lowering: Some(0.05),
                },
            },
            ..SweepRequest::default()
        };
        let args = request
            .task_arguments(Some(Path::new("/j/params.toml")))
            .unwrap();
        assert_eq!(
            args.join(" "),
            "sweep --kind=single,delayed --model=eq1-linear,eq4 --phi=0.57:0.62:0.01 --freq=12.5 \
             --tau=0:0.1:0.05 --rtol=0.000000001 --params=/j/params.toml --link=sil \
             --gain-lowering=0.05"
        );
        let uneven = SweepRequest {
            spec: SweepSpec {
                phis: vec![0.57, 0.6, 0.61],
                ..SweepSpec::default()
            },
            ..SweepRequest::default()
        };
        let e = uneven.task_arguments(None).unwrap_err();
        assert!(e.to_string().contains("--phi"), "{e}");
    }
}
