//! What every rig program leaves behind: its acquisition log (the logs' own format, built with
//! [`SampleLogBuilder`] from the controller's sample records exactly as they arrived) and a
//! figure of commanded vs measured motor position and the force command.

use crate::error::RigError;
use sandjumper_acqlog::{AcqLog, LogMetadata, SampleLogBuilder};
use sandjumper_core::SampleRecord;
use sandjumper_core::sample::flags;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::palette;
use std::path::{Path, PathBuf};

/// The acquisition log of `samples` at `tick_hz` and `metres_per_count`, with `source` (the
/// command) and `firmware` (who ran it) in its metadata; `fill` adds the rest.
pub fn samples_log(
    samples: &[SampleRecord],
    tick_hz: u32,
    metres_per_count: f64,
    firmware: String,
    source: String,
    fill: impl FnOnce(&mut LogMetadata),
) -> Result<AcqLog, RigError> {
    let mut meta = LogMetadata::new(f64::from(tick_hz), 1.0 / metres_per_count);
    meta.firmware = Some(firmware);
    meta.source = Some(source);
    fill(&mut meta);
    let mut builder = SampleLogBuilder::new(meta);
    for s in samples {
        builder
            .push(s)
            .map_err(|e| RigError::internal(format!("the controller's samples: {e}")))?;
    }
    Ok(builder.finish())
}

/// Who ran the program, for the log's `firmware` line.
pub fn firmware_name(link: &str) -> String {
    let version = env!("CARGO_PKG_VERSION");
    if link == "sil" {
        format!("sandjumper-core {version} (software in the loop)")
    } else {
        format!("sandjumper-firmware {version} ({link})")
    }
}

/// Index of the first sample of the trajectory (the first `Running` record).
pub fn start_index(samples: &[SampleRecord]) -> Option<usize> {
    samples.iter().position(|s| s.flags & flags::RUNNING != 0)
}

/// Commanded vs measured motor position and the force command against time since the start.
pub fn motion_figure(
    samples: &[SampleRecord],
    tick_hz: u32,
    metres_per_count: f64,
    title: String,
) -> LineFigure {
    let t0 = start_index(samples).map_or(0, |i| samples[i].tick);
    let step = (samples.len() / 4000).max(1);
    let t = |s: &SampleRecord| f64::from(s.tick.wrapping_sub(t0) as i32) / f64::from(tick_hz);
    let pts = |f: &dyn Fn(&SampleRecord) -> f64| -> Vec<(f64, f64)> {
        samples.iter().step_by(step).map(|s| (t(s), f(s))).collect()
    };
    let line = |label: &str, i: usize, dashed: bool, points| Line {
        label: label.into(),
        points,
        color: palette(i),
        dashed,
        markers: false,
    };
    let panels = vec![
        LinePanel {
            caption: "motor position relative to the rod".into(),
            x_desc: "time since the trajectory started (s)".into(),
            y_desc: "p (mm)".into(),
            lines: vec![
                line(
                    "commanded",
                    0,
                    true,
                    pts(&|s| 1e3 * f64::from(s.commanded_position_m)),
                ),
                line(
                    "measured (encoder)",
                    1,
                    false,
                    pts(&|s| 1e3 * s.encoder_count as f64 * metres_per_count),
                ),
            ],
            y_from_zero: false,
        },
        LinePanel {
            caption: "force command".into(),
            x_desc: "time since the trajectory started (s)".into(),
            y_desc: "F_m command (N)".into(),
            lines: vec![line(
                "force command",
                2,
                false,
                pts(&|s| f64::from(s.force_n)),
            )],
            y_from_zero: false,
        },
    ];
    LineFigure {
        title,
        size: grid_size(panels.len()),
        panels,
    }
}

/// Write `acquisition.csv` (and with `mcap` `acquisition.mcap`), `params.toml`,
/// `summary.json` and `<stem>.png`/`.svg` into the staged directory, then commit it. Returns
/// the directory.
pub fn write_run_files(
    staged: sandjumper_output::StagedDir,
    log: &AcqLog,
    params: &sandjumper_model::params::Params,
    summary_json: &str,
    figure: &LineFigure,
    stem: &str,
    mcap: bool,
) -> Result<std::path::PathBuf, RigError> {
    log.write_file(&staged.file("acquisition.csv"))
        .map_err(|e| RigError::internal(format!("cannot write acquisition.csv: {e}")))?;
    if mcap {
        log.write_mcap_file(&staged.file("acquisition.mcap"), None)
            .map_err(|e| RigError::internal(format!("cannot write acquisition.mcap: {e}")))?;
    }
    staged.write_text("params.toml", &params.to_toml())?;
    staged.write_text("summary.json", &format!("{summary_json}\n"))?;
    sandjumper_output::plot::save_figure(
        figure,
        &staged.file(&format!("{stem}.png")),
        Some(&staged.file(&format!("{stem}.svg"))),
    )?;
    Ok(staged.commit()?)
}

/// Largest `|p_cmd - p|` over the trajectory's samples (Running or Done), m.
pub fn max_tracking_error_m(samples: &[SampleRecord], metres_per_count: f64) -> f64 {
    samples
        .iter()
        .filter(|s| s.flags & (flags::RUNNING | flags::DONE) != 0)
        .map(|s| {
            (f64::from(s.commanded_position_m) - s.encoder_count as f64 * metres_per_count).abs()
        })
        .fold(0.0, f64::max)
}

pub use crate::hil::open::FaultEntry;

/// The faults of a run, for summaries.
pub fn fault_entries(faults: &[sandjumper_core::protocol::FaultReport]) -> Vec<FaultEntry> {
    faults.iter().map(FaultEntry::of).collect()
}

/// The simulated robot (sil/pil) with the motor at `p0_m`, or `None` for a board.
pub fn robot_fixture(
    simulated: bool,
    params: &sandjumper_model::params::Params,
    model: sandjumper_model::params::ModelName,
    p0_m: f64,
    config: crate::hil::rig_model::RigModelConfig,
) -> Result<Option<crate::hil::rig_model::RigModel>, RigError> {
    if !simulated {
        return Ok(None);
    }
    let opts = sandjumper_model::options::SimOptions {
        rtol: crate::hil::run::DEFAULT_RTOL,
        ..sandjumper_model::options::SimOptions::default()
    };
    crate::hil::rig_model::RigModel::new(params, model, p0_m, config, &opts)
        .map(Some)
        .map_err(|e| RigError::input(e.to_string()))
}

/// What a rig program's outcome (a `JumpOutcome`, a `ReplayOutcome`, an `IntrudeOutcome`, or
/// `hil`'s `HilJump`) gives the command that ran it: its folder, what
/// it prints and whether the run went cleanly.
pub trait ProgramOutcome: std::fmt::Display {
    /// `summary.json`'s text (pretty JSON, no newline).
    fn json(&self) -> Result<String, RigError>;
    /// The faults the controller reported, in order.
    fn faults(&self) -> &[FaultEntry];
    /// Write the program's files into `staged` (acquisition.mcap too with `mcap`) and commit
    /// it; returns the folder.
    fn write(&self, staged: sandjumper_output::StagedDir, mcap: bool) -> Result<PathBuf, RigError>;
    /// Whether the controller completed the program cleanly, once its folder `dir` is written
    /// (an internal error, exit 1, naming the folder, when it did not).
    fn check(&self, dir: &Path) -> Result<(), RigError>;
    /// Whether the controller completed the program with no fault ([`ProgramOutcome::check`]'s
    /// test, for a caller that wrote no folder).
    fn completed_cleanly(&self) -> bool;
    /// The acquisition log the run recorded (what acquisition.csv holds).
    fn acquisition_log(&self) -> AcqLog;

    /// What the command prints on stdout: the JSON (`as_json`) or the summary and one line
    /// per fault, each ending in a newline.
    fn printed(&self, as_json: bool) -> Result<String, RigError> {
        printed(self, as_json)
    }
}

/// [`ProgramOutcome::printed`]'s own text: the JSON (`as_json`) or the summary and one line
/// per fault, each ending in a newline.
pub fn printed<O: ProgramOutcome + ?Sized>(outcome: &O, as_json: bool) -> Result<String, RigError> {
    if as_json {
        return Ok(format!("{}\n", outcome.json()?));
    }
    let mut text = outcome.to_string();
    for f in outcome.faults() {
        text.push_str(&format!(
            "  fault {} {} at tick {}\n",
            f.code, f.name, f.tick
        ));
    }
    Ok(text)
}

/// [`ProgramOutcome`] for an outcome whose inherent `json`, `write` and `check` and field
/// `faults` it delegates to.
macro_rules! program_outcome {
    ($t:ty) => {
        impl $crate::tool::output::ProgramOutcome for $t {
            fn json(&self) -> Result<String, RigError> {
                <$t>::json(self)
            }
            fn faults(&self) -> &[$crate::hil::open::FaultEntry] {
                &self.faults
            }
            fn write(
                &self,
                staged: sandjumper_output::StagedDir,
                mcap: bool,
            ) -> Result<std::path::PathBuf, RigError> {
                <$t>::write(self, staged, mcap)
            }
            fn check(&self, dir: &std::path::Path) -> Result<(), RigError> {
                <$t>::check(self, dir)
            }
            fn completed_cleanly(&self) -> bool {
                self.completed && self.faults.is_empty()
            }
            fn acquisition_log(&self) -> sandjumper_acqlog::AcqLog {
                self.log.clone()
            }
        }
    };
}
pub(crate) use program_outcome;

/// A rig program's request as a command runs it: checked before anything opens (a live
/// view, the output folder, the link), then run.
pub trait ProgramRequest {
    /// What the check found that the run needs (the replay's plan).
    type Checked;
    /// What the run gives.
    type Outcome: ProgramOutcome;
    /// Refuse, before anything runs, what the program cannot do.
    fn check(&self) -> Result<Self::Checked, RigError>;
    /// Run the checked program, `watch` shown every step.
    fn run_checked(
        &self,
        checked: Self::Checked,
        progress: &dyn sandjumper_output::Progress,
        watch: Option<&mut dyn crate::watch::RunWatch>,
    ) -> Result<Self::Outcome, RigError>;
}

/// [`ProgramRequest`] for a request checked by its `validate` and run by `$run` (its
/// module's `run_watching`), invoked in that module.
macro_rules! validated_program {
    ($request:ident, $outcome:ident, $run:ident) => {
        impl $crate::tool::output::ProgramRequest for $request {
            type Checked = ();
            type Outcome = $outcome;
            fn check(&self) -> Result<(), RigError> {
                self.validate()
            }
            fn run_checked(
                &self,
                (): (),
                progress: &dyn sandjumper_output::Progress,
                watch: Option<&mut dyn crate::watch::RunWatch>,
            ) -> Result<Self::Outcome, RigError> {
                $run(self, progress, watch)
            }
        }
    };
}
pub(crate) use validated_program;
