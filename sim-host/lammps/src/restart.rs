//! Restart files and resumed stages.
//!
//! Each LAMMPS stage (`settle`, `intrude`) writes a restart file every so many steps
//! (`restart/STAGE.STEP`, LAMMPS's `restart` command). A run killed (a cluster's time limit,
//! `kill -9`, a node lost) leaves them in its unfinished folder; the same command on the same
//! output runs the stage again from the newest one ([`run_stage`]). Only the newest two are
//! kept while a stage runs: the newest may be the one LAMMPS is writing, the other is whole.
//! One LAMMPS cannot read (cut short by the kill) is set aside as `FILE.unreadable` and the
//! next older one tried.
//!
//! A resumed run is not the unbroken run to the last digit: LAMMPS's granular contacts depend
//! on the grains' velocities, which a restart gives at the full step where the unbroken run
//! had them at the half step, and the atoms' order (and so the sums' rounding) changes, as it
//! does on another number of ranks. The foot's path and the clock are the same to the last
//! digit; the contacts' forces drift apart as the same run's do on another decomposition
//! (docs/dem.md states by how much).

use std::cell::Cell;
use std::path::{Path, PathBuf};

use sandjumper_output::Progress;

use crate::lammps::{Lammps, RunReport};
use crate::script::Resume;

/// The restart files of `stage` in `dir/restart`, newest first, with their steps.
pub fn restarts(dir: &Path, stage: &str) -> Vec<(u64, PathBuf)> {
    let prefix = format!("{stage}.");
    let Ok(entries) = std::fs::read_dir(dir.join("restart")) else {
        return Vec::new();
    };
    let mut found: Vec<(u64, PathBuf)> = entries
        .filter_map(Result::ok)
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let step = name.strip_prefix(&prefix)?.parse::<u64>().ok()?;
            Some((step, e.path()))
        })
        .collect();
    found.sort_by_key(|f| std::cmp::Reverse(f.0));
    found
}

/// Remove every restart file of `stage` (it is done).
pub fn remove_all(dir: &Path, stage: &str) {
    for (_, file) in restarts(dir, stage) {
        let _ = std::fs::remove_file(file);
    }
}

/// Remove all but the newest two restart files of `stage`.
pub fn prune(dir: &Path, stage: &str) {
    for (_, old) in restarts(dir, stage).into_iter().skip(2) {
        let _ = std::fs::remove_file(old);
    }
}

/// Cut the time series `name` (`force.txt`, `column.txt`: LAMMPS's `fix ave/time`) in `dir`
/// to its header and the rows of steps at or before `step` (the resumed stage appends the
/// rows after it).
pub fn cut_time_series(dir: &Path, name: &str, step: u64) -> Result<(), String> {
    let path = dir.join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_default();
    let kept: String = text
        .lines()
        .filter(|l| {
            // A header, or a whole row (four numbers: a row the kill cut short is dropped) of a
            // step up to `step`.
            let words: Vec<&str> = l.split_whitespace().collect();
            l.starts_with('#')
                || (words.len() == 4
                    && words.iter().all(|w| w.parse::<f64>().is_ok())
                    && words[0].parse::<u64>().is_ok_and(|s| s <= step))
        })
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&path, kept).map_err(|e| format!("{}: {e}", path.display()))
}

/// Whether the LAMMPS log `log` shows a run that stopped inside `read_restart`: the command
/// echoed, its closing timing line (`read_restart CPU = ...`) never printed.
pub fn failed_reading(log: &Path) -> bool {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    text.lines()
        .any(|l| l.trim_start().starts_with("read_restart "))
        && !text.contains("read_restart CPU")
}

/// One stage to run: its name for restart files and logs, its input's name, and how to
/// write its input from the start or from a restart file.
pub struct Stage<'a> {
    /// `settle` or `intrude`: the restart files' and the log's name.
    pub name: &'a str,
    /// The input file to write (`in.settle`).
    pub input: &'a str,
    /// Its text from the start (`None`) or from a restart file.
    pub script: &'a dyn Fn(Option<Resume>) -> Result<String, String>,
    /// What to do before it runs from a step (`Some`) or from the start (`None`): cut an
    /// output file LAMMPS will append to.
    pub prepare: &'a dyn Fn(Option<u64>) -> Result<(), String>,
}

/// How a stage ran: LAMMPS's report of its last attempt and the step it resumed from.
#[derive(Clone, Debug, PartialEq)]
pub struct StageRun {
    /// The last attempt's report (its wall time is that attempt's).
    pub report: RunReport,
    /// The step the last attempt started from (`None`: the stage's start).
    pub resumed_from: Option<u64>,
}

/// Run `stage` in `dir` on `ranks` ranks: from its newest restart file when there is one,
/// else from its start. `on_step` sees every step LAMMPS reports and returns false to stop
/// it. Restart files beyond the newest two are removed as it runs.
pub fn run_stage(
    lammps: &Lammps,
    dir: &Path,
    ranks: u32,
    stage: &Stage,
    progress: &dyn Progress,
    on_step: &mut dyn FnMut(u64) -> bool,
) -> Result<StageRun, String> {
    std::fs::create_dir_all(dir.join("restart")).map_err(|e| e.to_string())?;
    let candidates: Vec<Option<(u64, PathBuf)>> = restarts(dir, stage.name)
        .into_iter()
        .map(Some)
        .chain([None])
        .collect();
    for candidate in candidates {
        let file = candidate
            .as_ref()
            .map(|(_, p)| format!("restart/{}", p.file_name().unwrap_or_default().display()));
        let resume = candidate
            .as_ref()
            .zip(file.as_deref())
            .map(|((step, _), file)| Resume { file, step: *step });
        (stage.prepare)(resume.map(|r| r.step))?;
        std::fs::write(dir.join(stage.input), (stage.script)(resume)?)
            .map_err(|e| format!("{}: {e}", dir.join(stage.input).display()))?;
        let log = match resume {
            None => format!("log.{}", stage.name),
            Some(r) => {
                progress.note(&format!(
                    "dem lammps: the {} resumed from its restart file of step {} ({})",
                    if stage.name == "intrude" {
                        "intrusion"
                    } else {
                        stage.name
                    },
                    r.step,
                    r.file
                ));
                format!("log.{}.from-{}", stage.name, r.step)
            }
        };
        let seen = Cell::new(false);
        let mut step = |s: u64| {
            seen.set(true);
            prune(dir, stage.name);
            on_step(s)
        };
        match lammps.run(dir, stage.input, &log, ranks, &mut step) {
            Ok(report) => {
                return Ok(StageRun {
                    report,
                    resumed_from: resume.map(|r| r.step),
                });
            }
            // LAMMPS failed while it read the restart file (cut short while it was written):
            // set aside; the next older one is tried. Any other failure (a launcher that did not
            // start, a processor grid that is not one world) keeps every restart file.
            Err(e) if !seen.get() && !progress.cancelled() && failed_reading(&dir.join(&log)) => {
                let Some((_, path)) = candidate else {
                    return Err(e);
                };
                let mut aside = path.clone().into_os_string();
                aside.push(".unreadable");
                progress.note(&format!(
                    "dem lammps: LAMMPS cannot resume from {} ({e}); it is set aside as {} and \
                     an older one tried",
                    path.display(),
                    PathBuf::from(&aside).display()
                ));
                std::fs::rename(&path, &aside).map_err(|e| e.to_string())?;
            }
            Err(e) => return Err(e),
        }
    }
    unreachable!("the last candidate is the stage's start, whose failure returns")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restart_files_are_listed_newest_first_and_pruned_to_two() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("restart")).unwrap();
        for name in [
            "intrude.1000",
            "intrude.3000",
            "intrude.2000",
            "settle.500",
            "intrude.x",
            "intrude.4000.unreadable",
        ] {
            std::fs::write(dir.path().join("restart").join(name), "").unwrap();
        }
        let steps: Vec<u64> = restarts(dir.path(), "intrude")
            .iter()
            .map(|r| r.0)
            .collect();
        assert_eq!(steps, [3000, 2000, 1000]);
        prune(dir.path(), "intrude");
        let steps: Vec<u64> = restarts(dir.path(), "intrude")
            .iter()
            .map(|r| r.0)
            .collect();
        assert_eq!(steps, [3000, 2000]);
        assert_eq!(
            restarts(dir.path(), "settle").len(),
            1,
            "another stage's kept"
        );
        assert!(dir.path().join("restart/intrude.4000.unreadable").is_file());
    }

    #[test]
    fn the_force_file_is_cut_at_the_restart_step() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("force.txt"),
            "# Time-averaged data\n# TimeStep v_t\n50 0.1 1 2\n100 0.2 2 2\n150 0.3 3 2\n200 0.",
        )
        .unwrap();
        cut_time_series(dir.path(), "force.txt", 100).unwrap();
        // A log that stopped inside read_restart, and one that read it.
        let log = dir.path().join("log");
        std::fs::write(
            &log,
            "LAMMPS\nread_restart restart/intrude.600\nERROR: Unexpected end\n",
        )
        .unwrap();
        assert!(failed_reading(&log));
        std::fs::write(
            &log,
            "read_restart restart/intrude.600\n  read_restart CPU = 0.1\nERROR: x\n",
        )
        .unwrap();
        assert!(!failed_reading(&log));
        std::fs::write(&log, "srun: error\n").unwrap();
        assert!(!failed_reading(&log));
        assert_eq!(
            std::fs::read_to_string(dir.path().join("force.txt")).unwrap(),
            "# Time-averaged data\n# TimeStep v_t\n50 0.1 1 2\n100 0.2 2 2\n"
        );
    }
}
