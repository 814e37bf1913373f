//! `rig replay LOG` / `rig replay --stroke stroke.csv`: run a recorded (or edited)
//! motor trajectory, or a stroke file (`sandjumper optimize`'s answer, a replay's own
//! `table.csv`, or a [`StrokeTable`] in memory), on the rig.
//!
//! 1. Read the log (the acquisition-log format) and take `p(t)` from its encoder record; or
//!    read the stroke file (`t_s,p_m` at a fixed rate).
//! 2. Edit: `--clip START:END` (seconds from the log's first sample), `--time-stretch X`
//!    (`t -> X t`: above 1 slower), `--scale X` (`p -> X p`, about mid-stroke `p = 0`, where the
//!    one-cycle sines are centred).
//! 3. Resample at `--table-rate` (linear interpolation) into the core's replay table.
//!    A stroke file already at `--table-rate` is uploaded sample for sample.
//! 4. Refuse, before anything is sent, a table that fails the rig's feasibility check
//!    ([`StrokeTable::check`]): it leaves the stroke (`|p| <= 25 mm`), its motor force would
//!    exceed the drive's peak force, or it does not fit the firmware's buffer
//!    ([`REPLAY_CAPACITY`] samples). The force is the motor's on a standing rod,
//!    `m_m (p'' + g)`, with `p''` the table's second difference (what the controller's
//!    feedforward sees): the push-off, where the rod barely moves, is where the force peaks.
//! 5. Upload in chunks (`ReplayBegin`, `ReplayChunk` x n, `ReplayCommit` with the CRC-32),
//!    verify that the controller's committed checksum is the host's, run the replay and record
//!    the new log. The summary compares the measured motor trajectory with the table.

use std::fmt::{self, Write as _};
use std::path::{Path, PathBuf};

use serde::Serialize;

use sandjumper_acqlog::{AcqLog, ReadOptions};
use sandjumper_core::replay::{REPLAY_CAPACITY, replay_checksum};
use sandjumper_core::trajectory::STROKE_M;
use sandjumper_core::{JumpConfig, TrajectorySpec};
use sandjumper_model::params::{ModelName, Params};
use sandjumper_output::parse::number_within;
use sandjumper_output::plot::lines::LineFigure;
use sandjumper_output::{Progress, StagedDir};

use super::output::{
    FaultEntry, fault_entries, firmware_name, max_tracking_error_m, motion_figure, robot_fixture,
    samples_log, start_index, write_run_files,
};
use super::session::{Fixture, Program, bring_to_idle};
use super::target::Target;
use super::watched::{completed_cleanly, run_watched};
use crate::error::{RigError, to_json};
use crate::hil::rig_model::RigModelConfig;
use crate::hil::run::HilSpec;
use crate::hil::virtual_board::VirtualLoad;
use crate::protocol::link::{LinkError, RigLink};
use crate::stroke_table::{RigLimits, StrokeTable, TableRefusal};
use crate::watch::RunWatch;

/// A `START:END` window, s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clip {
    /// Start, s from the log's first sample.
    pub start_s: f64,
    /// End, s.
    pub end_s: f64,
}

/// The table to upload, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayPlan {
    /// Positions, m, one every `period_ticks`.
    pub samples: Vec<f32>,
    /// Control ticks between samples.
    pub period_ticks: u32,
    /// Table sample rate, Hz.
    pub rate_hz: f64,
    /// CRC-32 of the samples.
    pub checksum: u32,
    /// Largest |p|, m.
    pub max_abs_p_m: f64,
    /// Estimated peak motor force, N.
    pub peak_force_n: f64,
    /// The checked table (f64 samples).
    pub table: StrokeTable,
}

/// What is replayed: a log's encoder record or a stroke table.
#[derive(Clone, Debug)]
pub enum ReplaySource {
    /// An acquisition log.
    Log(Box<AcqLog>),
    /// A stroke table (a stroke file, or one in memory).
    Stroke(StrokeTable),
}

impl ReplaySource {
    /// The acquisition log at `path` (`allow_gaps`: accept gaps, interpolated).
    pub fn read_log(path: &Path, allow_gaps: bool) -> Result<Self, RigError> {
        AcqLog::read_file(
            path,
            &ReadOptions {
                allow_gaps,
                ..ReadOptions::default()
            },
        )
        .map(|l| Self::Log(Box::new(l)))
        .map_err(|e| RigError::input(format!("{}: {e}", path.display())))
    }

    /// What `rig replay` replays: the stroke file `stroke` if given, else the log `log`
    /// (`allow_gaps`: accept gaps, interpolated); with the name messages and the summary give
    /// it (the path as given).
    pub fn read(
        log: Option<&Path>,
        stroke: Option<&Path>,
        allow_gaps: bool,
    ) -> Result<(Self, String), RigError> {
        let source = match (log, stroke) {
            (_, Some(path)) => Self::read_stroke(path),
            (Some(path), None) => Self::read_log(path, allow_gaps),
            (None, None) => Err(RigError::input(
                "rig replay needs a LOG.csv or --stroke FILE",
            )),
        }?;
        let name = stroke.or(log).unwrap_or(Path::new("-"));
        Ok((source, name.display().to_string()))
    }

    /// The stroke file at `path` (`t_s,p_m` at a fixed rate).
    pub fn read_stroke(path: &Path) -> Result<Self, RigError> {
        StrokeTable::read_csv(path)
            .map(Self::Stroke)
            .map_err(RigError::Input)
    }

    /// `(t, p)` from the first sample, s and m.
    fn points(&self) -> Vec<(f64, f64)> {
        match self {
            Self::Log(log) => {
                let t0 = log.rows.first().map_or(0.0, |r| r.t_s);
                log.rows
                    .iter()
                    .zip(log.positions_m())
                    .map(|(r, p)| (r.t_s - t0, p))
                    .collect()
            }
            Self::Stroke(t) => t.points(),
        }
    }

    /// Duration, s.
    fn duration_s(&self) -> f64 {
        match self {
            Self::Log(log) => log.duration_s(),
            Self::Stroke(t) => t.duration_s(),
        }
    }
}

/// `rig replay`: what is replayed, how it is edited, and the rig it runs on.
#[derive(Clone, Debug)]
pub struct ReplayRequest {
    /// The controller.
    pub target: Target,
    /// The log or stroke table replayed.
    pub source: ReplaySource,
    /// Its name in messages, the summary's `source_log` and the log's `replay_of` (the path
    /// as given).
    pub source_name: String,
    /// Multiply the positions by this (about mid-stroke p = 0; 0 < X <= 10; default 1).
    pub scale: f64,
    /// Stretch time by this (above 1: slower; 0 < X <= 10; default 1).
    pub time_stretch: f64,
    /// Replay only this window, s from the source's first sample (before stretching).
    pub clip: Option<Clip>,
    /// Samples per second of the uploaded table, Hz (`None`: 1000 for a log, the table's own
    /// rate for a stroke).
    pub table_rate_hz: Option<u32>,
    /// Ground model of the simulated sand.
    pub model: ModelName,
    /// The parameters (the simulated rig's; motor mass and peak force for the force check).
    pub params: Params,
}

impl ReplayRequest {
    /// Replay `table` (named `name`) unedited on `target`, at its own rate: eq4, the
    /// phi = 0.57 preset.
    pub fn stroke(target: Target, table: StrokeTable, name: impl Into<String>) -> Self {
        Self {
            target,
            source: ReplaySource::Stroke(table),
            source_name: name.into(),
            scale: 1.0,
            time_stretch: 1.0,
            clip: None,
            table_rate_hz: None,
            model: ModelName::Eq4,
            params: Params::default(),
        }
    }

    /// `(t, p)` of the source after clipping, stretching and scaling; t from 0. Without edits
    /// a stroke table's own samples, unchanged.
    pub fn edited_record(&self) -> Result<Vec<(f64, f64)>, RigError> {
        let source = &self.source;
        let duration = source.duration_s();
        let (from, to) = match self.clip {
            Some(c) if c.start_s >= duration => {
                return Err(RigError::input(format!(
                    "--clip {}:{} starts after the end of {} ({duration} s)",
                    c.start_s, c.end_s, self.source_name
                )));
            }
            Some(c) => (c.start_s, c.end_s.min(duration)),
            None => (0.0, duration),
        };
        let points = source.points();
        if self.clip.is_none() && self.time_stretch == 1.0 && self.scale == 1.0 {
            return Ok(points);
        }
        let pts: Vec<(f64, f64)> = points
            .into_iter()
            .filter(|(t, _)| *t >= from - 1e-12 && *t <= to + 1e-12)
            .map(|(t, p)| ((t - from) * self.time_stretch, p * self.scale))
            .collect();
        if pts.len() < 2 {
            return Err(RigError::input(format!(
                "{}: fewer than 2 samples to replay{}",
                self.source_name,
                if self.clip.is_some() {
                    " inside --clip"
                } else {
                    ""
                }
            )));
        }
        Ok(pts)
    }

    /// The table to upload: the edited record resampled and checked (refused before anything
    /// moves, the source named).
    pub fn plan(&self) -> Result<ReplayPlan, RigError> {
        let record = self.edited_record()?;
        let rate = match (&self.source, self.table_rate_hz) {
            (_, Some(r)) => r,
            (ReplaySource::Stroke(t), None) => t.rate_hz,
            (ReplaySource::Log(_), None) => 1000,
        };
        let p = &self.params;
        plan(
            &record,
            rate,
            RigModelConfig::default().tick_hz,
            p.robot.motor_mass_kg,
            p.robot.gravity_m_s2,
            p.drive.peak_force_n,
        )
        .map_err(|e| RigError::input(format!("{}: {e}", self.source_name)))
    }
}

/// Resample `record` at `rate_hz` and check stroke, force and buffer (the rig's feasibility
/// check, [`StrokeTable::check`]). `motor_mass_kg` kg, `gravity` m/s^2, `peak_force_n` the
/// drive's limit, N.
pub fn plan(
    record: &[(f64, f64)],
    rate_hz: u32,
    tick_hz: u32,
    motor_mass_kg: f64,
    gravity: f64,
    peak_force_n: f64,
) -> Result<ReplayPlan, RigError> {
    let limits = RigLimits {
        motor_mass_kg,
        gravity_m_s2: gravity,
        peak_force_n,
        stroke_m: STROKE_M,
        capacity: REPLAY_CAPACITY,
    };
    let table = StrokeTable::resample(record, rate_hz);
    let period_ticks = table
        .period_ticks(tick_hz)
        .map_err(|e| RigError::input(format!("--table-rate: {e}")))?;
    let check = table.check(&limits).map_err(|e| {
        let hint = match e {
            TableRefusal::TooShort { .. } => "",
            TableRefusal::TooLong { .. } => ". Shorten it with --clip, or lower --table-rate",
            TableRefusal::Stroke { .. } => "; lower --scale",
            TableRefusal::Force { .. } => {
                "; slow it down with --time-stretch above 1 or lower --scale"
            }
        };
        RigError::input(format!("refused before anything moved: {e}{hint}"))
    })?;
    let samples = table.samples_f32();
    Ok(ReplayPlan {
        checksum: replay_checksum(&samples),
        samples,
        period_ticks,
        rate_hz: f64::from(rate_hz),
        max_abs_p_m: check.max_abs_p_m,
        peak_force_n: check.peak_force_n,
        table,
    })
}

/// Upload `plan` in chunks and verify the controller's committed checksum.
pub fn upload(link: &mut dyn RigLink, plan: &ReplayPlan) -> Result<(), LinkError> {
    plan.table
        .upload(link, plan.period_ticks * plan.table.rate_hz)
        .map(|_| ())
}

/// `summary.json` of `rig replay` (the serialised fields), and what its folder holds.
#[derive(Serialize)]
pub struct ReplayOutcome {
    /// The link.
    pub link: String,
    /// The replayed log (or stroke).
    pub source_log: String,
    /// Edits.
    pub scale: f64,
    /// Edits.
    pub time_stretch: f64,
    /// Edits: `[start, end]` s.
    pub clip_s: Option<[f64; 2]>,
    /// Table samples uploaded.
    pub table_samples: usize,
    /// Table sample rate, Hz.
    pub table_rate_hz: f64,
    /// The verified CRC-32 of the table.
    pub checksum: String,
    /// Largest |p| of the table, m.
    pub max_abs_p_m: f64,
    /// Estimated peak motor force, N.
    pub peak_force_estimate_n: f64,
    /// The controller finished the replay.
    pub completed: bool,
    /// Faults reported.
    pub faults: Vec<FaultEntry>,
    /// Sample records received.
    pub samples: usize,
    /// Sample records lost.
    pub dropped_samples: u64,
    /// Largest |p_cmd - p| while running, m.
    pub tracking_error_max_m: f64,
    /// Largest |p_measured - p_table| over the replay, m (the reproduction of the trajectory).
    pub reproduction_error_max_m: f64,
    /// RMS of the same, m.
    pub reproduction_error_rms_m: f64,
    /// Jump height of the simulated rig (sil/pil/f407), m.
    pub simulated_jump_height_m: Option<f64>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// What was uploaded (`table.csv`).
    #[serde(skip)]
    pub plan: ReplayPlan,
    /// The new acquisition log.
    #[serde(skip)]
    pub log: AcqLog,
    /// The parameters run.
    #[serde(skip)]
    pub params: Params,
    /// Commanded vs measured motor position and the force command.
    #[serde(skip)]
    pub figure: LineFigure,
}

impl fmt::Display for ReplayOutcome {
    /// The line `rig replay` prints without `--json` (with its newline).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "rig replay through {}: {} table samples at {} Hz (checksum {} verified), {}; \
             reproduction error max {:.3} mm, rms {:.3} mm",
            self.link,
            self.table_samples,
            self.table_rate_hz,
            self.checksum,
            if self.completed {
                "completed"
            } else {
                "NOT completed"
            },
            1e3 * self.reproduction_error_max_m,
            1e3 * self.reproduction_error_rms_m
        )
    }
}

impl ReplayOutcome {
    /// The names of the faults reported, in order.
    pub fn fault_names(&self) -> Vec<&'static str> {
        self.faults.iter().map(|f| f.name).collect()
    }

    /// `summary.json`'s text (pretty JSON, no newline).
    pub fn json(&self) -> Result<String, RigError> {
        to_json(self, "the summary")
    }

    /// Write table.csv, acquisition.csv (and with `mcap` acquisition.mcap), params.toml,
    /// summary.json, replay.png and replay.svg into `staged`, then commit it.
    pub fn write(&self, staged: StagedDir, mcap: bool) -> Result<PathBuf, RigError> {
        let json = self.json()?;
        staged.write_text("table.csv", &table_csv(&self.plan))?;
        write_run_files(
            staged,
            &self.log,
            &self.params,
            &json,
            &self.figure,
            "replay",
            mcap,
        )
    }

    /// Whether the replay completed cleanly, once its folder `dir` is written.
    pub fn check(&self, dir: &Path) -> Result<(), RigError> {
        completed_cleanly("replay", self.completed, &self.faults, dir)
    }
}

fn table_csv(plan: &ReplayPlan) -> String {
    let mut s = String::from("t_s,p_m\n");
    for (k, p) in plan.samples.iter().enumerate() {
        let _ = writeln!(s, "{},{}", k as f64 / plan.rate_hz, p);
    }
    s
}

/// Largest and RMS `|p_measured - p_table|` over the replay's `duration` s, m.
fn reproduction_error(
    samples: &[sandjumper_core::SampleRecord],
    plan: &ReplayPlan,
    duration: f64,
    model_config: &RigModelConfig,
) -> (f64, f64) {
    let (mut worst, mut sum2, mut n) = (0.0f64, 0.0f64, 0usize);
    if let Some(start) = start_index(samples) {
        let t0 = samples[start].tick;
        let hz = f64::from(model_config.tick_hz);
        for s in &samples[start..] {
            let t = f64::from(s.tick.wrapping_sub(t0)) / hz;
            if t > duration {
                break;
            }
            let x = t * plan.rate_hz;
            let k = (x.floor() as usize).min(plan.samples.len() - 1);
            let k1 = (k + 1).min(plan.samples.len() - 1);
            let u = x - k as f64;
            let target =
                f64::from(plan.samples[k]) + u * f64::from(plan.samples[k1] - plan.samples[k]);
            let e = (s.encoder_count as f64 * model_config.metres_per_count - target).abs();
            worst = worst.max(e);
            sum2 += e * e;
            n += 1;
        }
    }
    (worst, if n > 0 { (sum2 / n as f64).sqrt() } else { 0.0 })
}

/// Run `rig replay`.
pub fn run(request: &ReplayRequest, progress: &dyn Progress) -> Result<ReplayOutcome, RigError> {
    let plan = request.plan()?;
    run_planned(request, plan, progress, None)
}

/// [`run`] with the plan already made ([`ReplayRequest::plan`]: the caller refuses a table
/// before anything else of its own starts), `watch` shown the run's title and every step.
pub fn run_planned(
    request: &ReplayRequest,
    plan: ReplayPlan,
    _progress: &dyn Progress,
    watch: Option<&mut dyn RunWatch>,
) -> Result<ReplayOutcome, RigError> {
    let params = &request.params;
    let model_config = RigModelConfig::default();
    let mut robot = robot_fixture(
        request.target.host_plays_the_rig(),
        params,
        request.model,
        plan.table.samples_m[0],
        model_config,
    )?;
    let mut link = request.target.open_with_load(
        &model_config,
        Some(VirtualLoad::Robot {
            params: params.clone(),
            model: request.model,
            p0_m: plan.table.samples_m[0],
        }),
    )?;
    let name = link.name();
    bring_to_idle(link.as_mut())
        .and_then(|()| upload(link.as_mut(), &plan))
        .map_err(|e| RigError::link(&name, "the replay upload", e))?;
    let duration = (plan.samples.len() - 1) as f64 / plan.rate_hz;
    let program = Program {
        config: JumpConfig {
            // The gains `rig jump` and `hil` run the carriage with.
            gains: HilSpec::rig_gains(&params.robot),
            ..JumpConfig::new(TrajectorySpec::Replay {
                checksum: plan.checksum,
            })
        },
        tick_hz: model_config.tick_hz,
        settle_s: 0.2,
        tail_s: 0.2,
        max_run_s: duration + 5.0,
    };
    let run = run_watched(
        watch,
        "replay",
        link.as_mut(),
        robot.as_mut().map(|r| r as &mut dyn Fixture),
        &program,
        None,
        model_config.metres_per_count,
    )
    .map_err(|e| RigError::link(&name, "the replay", e))?;
    let mpc = model_config.metres_per_count;
    let (worst, rms) = reproduction_error(&run.samples, &plan, duration, &model_config);
    let source = &request.source_name;
    let log = samples_log(
        &run.samples,
        model_config.tick_hz,
        mpc,
        firmware_name(&name),
        format!("sandjumper rig replay {source} ({name})"),
        |m| {
            let (jump, phi) = match &request.source {
                ReplaySource::Log(log) => (log.meta.jump.clone(), log.meta.phi),
                ReplaySource::Stroke(_) => (None, None),
            };
            m.jump = jump;
            m.phi = if request.target.is_simulated() {
                Some(params.sand.packing_fraction)
            } else {
                phi
            };
            m.extra.push(("replay_of".into(), source.clone()));
            m.extra
                .push(("replay_scale".into(), request.scale.to_string()));
            m.extra.push((
                "replay_time_stretch".into(),
                request.time_stretch.to_string(),
            ));
            m.extra
                .push(("replay_checksum".into(), format!("{:#010x}", plan.checksum)));
        },
    )?;
    let title = format!("rig replay of {source} through {name}");
    Ok(ReplayOutcome {
        link: name,
        source_log: source.clone(),
        scale: request.scale,
        time_stretch: request.time_stretch,
        clip_s: request.clip.map(|c| [c.start_s, c.end_s]),
        table_samples: plan.samples.len(),
        table_rate_hz: plan.rate_hz,
        checksum: format!("{:#010x}", plan.checksum),
        max_abs_p_m: plan.max_abs_p_m,
        peak_force_estimate_n: plan.peak_force_n,
        completed: run.completed,
        faults: fault_entries(&run.faults),
        samples: run.samples.len(),
        dropped_samples: log.meta.dropped_samples,
        tracking_error_max_m: max_tracking_error_m(&run.samples, mpc),
        reproduction_error_max_m: worst,
        reproduction_error_rms_m: rms,
        simulated_jump_height_m: robot
            .as_ref()
            .map(|r| r.plant().summary().jump_height_m)
            .or(run.report.simulated_jump_height_m),
        wall_time_s: run.wall_time_s,
        figure: motion_figure(&run.samples, model_config.tick_hz, mpc, title),
        plan,
        log,
        params: params.clone(),
    })
}

crate::tool::output::program_outcome!(ReplayOutcome);

/// The value parser of a positive factor (`--scale`, `--time-stretch`): 0 < X <= 10; `what`
/// names it in the message.
pub fn parse_factor(
    what: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        number_within(s, |v| v > 0.0 && v <= 10.0)
            .ok_or_else(|| format!("{what} `{s}` not allowed (allowed: 0 < X <= 10)"))
    }
}

/// `--clip START:END`: seconds from the log's first sample, 0 <= START < END.
pub fn parse_clip(s: &str) -> Result<Clip, String> {
    let bad =
        || format!("clip `{s}` not allowed (allowed: START:END in seconds, 0 <= START < END)");
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let num = |x: &str| number_within(x, |_| true);
    match (num(a), num(b)) {
        (Some(start_s), Some(end_s)) if start_s >= 0.0 && end_s > start_s => {
            Ok(Clip { start_s, end_s })
        }
        _ => Err(bad()),
    }
}

impl super::output::ProgramRequest for ReplayRequest {
    type Checked = ReplayPlan;
    type Outcome = ReplayOutcome;
    fn check(&self) -> Result<Self::Checked, RigError> {
        self.plan()
    }
    fn run_checked(
        &self,
        plan: Self::Checked,
        progress: &dyn sandjumper_output::Progress,
        watch: Option<&mut dyn crate::watch::RunWatch>,
    ) -> Result<Self::Outcome, RigError> {
        run_planned(self, plan, progress, watch)
    }
}
