//! `sandjumper rig replay LOG` / `rig replay --stroke stroke.csv`: run a recorded (or edited)
//! motor trajectory, or a stroke file (`sandjumper optimize`'s answer, a replay's own
//! `table.csv`), on the rig.
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

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use serde::Serialize;

use super::output::{
    FaultEntry, fault_entries, firmware_name, max_tracking_error_m, motion_figure, robot_fixture,
    samples_log, start_index, write_run_files,
};
use super::session::{Fixture, Program, bring_to_idle};
use super::{RigParamArgs, TargetArgs, conclude, link_failed, run_program_live, start_live};
use sandjumper_acqlog::{AcqLog, ReadOptions};
use sandjumper_core::replay::{REPLAY_CAPACITY, replay_checksum};
use sandjumper_core::trajectory::STROKE_M;
use sandjumper_core::{JumpConfig, TrajectorySpec};
use sandjumper_model::params::Params;
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_rig::hil::link::{LinkError, RigLink};
use sandjumper_rig::hil::rig_model::RigModelConfig;
use sandjumper_rig::hil::run::HilSpec;
use sandjumper_rig::hil::virtual_board::VirtualLoad;
use sandjumper_rig::stroke_table::{RigLimits, StrokeTable, TableRefusal};

fn factor(
    what: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 10.0 => Ok(v),
        _ => Err(format!("{what} `{s}` not allowed (allowed: 0 < X <= 10)")),
    }
}

/// A `START:END` window, s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clip {
    /// Start, s from the log's first sample.
    pub start_s: f64,
    /// End, s.
    pub end_s: f64,
}

fn parse_clip(s: &str) -> Result<Clip, String> {
    let bad =
        || format!("clip `{s}` not allowed (allowed: START:END in seconds, 0 <= START < END)");
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let num = |x: &str| x.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    match (num(a), num(b)) {
        (Some(start_s), Some(end_s)) if start_s >= 0.0 && end_s > start_s => {
            Ok(Clip { start_s, end_s })
        }
        _ => Err(bad()),
    }
}

/// `rig replay`.
#[derive(Debug, Clone, Args)]
pub struct ReplayArgs {
    /// The live view of the run.
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
    /// The acquisition log whose encoder record is replayed.
    #[arg(
        value_name = "LOG.csv",
        required_unless_present = "stroke",
        conflicts_with = "stroke"
    )]
    pub log: Option<PathBuf>,
    /// Replay a stroke file instead of a log: `t_s,p_m` rows at a fixed rate (what
    /// `sandjumper optimize` writes as stroke.csv; a replay's table.csv is one too).
    #[arg(long, value_name = "FILE")]
    pub stroke: Option<PathBuf>,
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// Multiply the positions by X (about mid-stroke p = 0).
    #[arg(long, value_name = "X", allow_negative_numbers = true, default_value = "1", value_parser = factor("scale"))]
    pub scale: f64,
    /// Stretch time by X (above 1: slower).
    #[arg(long, value_name = "X", allow_negative_numbers = true, default_value = "1", value_parser = factor("time stretch"))]
    pub time_stretch: f64,
    /// Replay only START:END, seconds from the log's first sample (before stretching).
    #[arg(long, value_name = "START:END", value_parser = parse_clip)]
    pub clip: Option<Clip>,
    /// Samples per second of the uploaded table (divides the 10 kHz control rate; default
    /// 1000 for a log, the file's own rate for --stroke).
    #[arg(long, value_name = "HZ", value_parser = clap::value_parser!(u32).range(10..=10_000))]
    pub table_rate: Option<u32>,
    /// Accept a log with gaps (interpolated).
    #[arg(long)]
    pub allow_gaps: bool,
    /// Simulated rig and parameters (motor mass and peak force for the force check).
    #[command(flatten)]
    pub rig: RigParamArgs,
    /// Write acquisition.csv (the new log), table.csv (what was uploaded), params.toml,
    /// summary.json, replay.png and replay.svg into DIR.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Also write the acquisition log as acquisition.mcap (for Foxglove, Lichtblick and
    /// PlotJuggler; see `sandjumper log convert`).
    #[arg(long)]
    pub mcap: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
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

/// What is replayed: a log's encoder record or a stroke file.
pub enum ReplaySource {
    /// An acquisition log.
    Log(Box<AcqLog>),
    /// A stroke file.
    Stroke(StrokeTable),
}

impl ReplaySource {
    /// Read the source `a` names.
    pub fn read(a: &ReplayArgs) -> Result<Self, CliError> {
        match (&a.log, &a.stroke) {
            (_, Some(path)) => StrokeTable::read_csv(path)
                .map(Self::Stroke)
                .map_err(CliError::input),
            (Some(path), None) => read_log(path, a.allow_gaps).map(|l| Self::Log(Box::new(l))),
            (None, None) => Err(CliError::input(
                "rig replay needs a LOG.csv or --stroke FILE".to_string(),
            )),
        }
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

/// The path of the replayed file.
fn source_path(a: &ReplayArgs) -> &Path {
    a.stroke
        .as_deref()
        .or(a.log.as_deref())
        .unwrap_or(Path::new("-"))
}

/// `(t, p)` of the source after clipping, stretching and scaling; t from 0. Without edits a
/// stroke file's own samples, unchanged.
pub fn edited_record(source: &ReplaySource, a: &ReplayArgs) -> Result<Vec<(f64, f64)>, CliError> {
    let duration = source.duration_s();
    let (from, to) = match a.clip {
        Some(c) if c.start_s >= duration => {
            return Err(CliError::input(format!(
                "--clip {}:{} starts after the end of {} ({duration} s)",
                c.start_s,
                c.end_s,
                source_path(a).display()
            )));
        }
        Some(c) => (c.start_s, c.end_s.min(duration)),
        None => (0.0, duration),
    };
    let points = source.points();
    if a.clip.is_none() && a.time_stretch == 1.0 && a.scale == 1.0 {
        return Ok(points);
    }
    let pts: Vec<(f64, f64)> = points
        .into_iter()
        .filter(|(t, _)| *t >= from - 1e-12 && *t <= to + 1e-12)
        .map(|(t, p)| ((t - from) * a.time_stretch, p * a.scale))
        .collect();
    if pts.len() < 2 {
        return Err(CliError::input(format!(
            "{}: fewer than 2 samples to replay{}",
            source_path(a).display(),
            if a.clip.is_some() {
                " inside --clip"
            } else {
                ""
            }
        )));
    }
    Ok(pts)
}

/// Resample `record` at `rate_hz` and check stroke, force and buffer (the rig's feasibility
/// check, [`StrokeTable::check`]). `m_m` kg, `g` m/s^2, `peak_force_n` the drive's limit.
pub fn plan(
    record: &[(f64, f64)],
    rate_hz: u32,
    tick_hz: u32,
    motor_mass_kg: f64,
    gravity: f64,
    peak_force_n: f64,
) -> Result<ReplayPlan, CliError> {
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
        .map_err(|e| CliError::input(format!("--table-rate: {e}")))?;
    let check = table.check(&limits).map_err(|e| {
        let hint = match e {
            TableRefusal::TooShort { .. } => "",
            TableRefusal::TooLong { .. } => ". Shorten it with --clip, or lower --table-rate",
            TableRefusal::Stroke { .. } => "; lower --scale",
            TableRefusal::Force { .. } => {
                "; slow it down with --time-stretch above 1 or lower --scale"
            }
        };
        CliError::input(format!("refused before anything moved: {e}{hint}"))
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

/// `summary.json` of `rig replay`.
#[derive(Debug, Serialize)]
pub struct ReplayReport {
    /// The link.
    pub link: String,
    /// The replayed log.
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
    /// Jump height of the simulated rig (sil/pil), m.
    pub simulated_jump_height_m: Option<f64>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
}

fn read_log(path: &Path, allow_gaps: bool) -> Result<AcqLog, CliError> {
    AcqLog::read_file(
        path,
        &ReadOptions {
            allow_gaps,
            ..ReadOptions::default()
        },
    )
    .map_err(|e| CliError::input(format!("{}: {e}", path.display())))
}

fn table_csv(plan: &ReplayPlan) -> String {
    let mut s = String::from("t_s,p_m\n");
    for (k, p) in plan.samples.iter().enumerate() {
        let _ = writeln!(s, "{},{}", k as f64 / plan.rate_hz, p);
    }
    s
}

/// Run `rig replay`.
pub fn run(a: &ReplayArgs) -> Result<(), CliError> {
    let params: Params = a.rig.resolve()?;
    let source = ReplaySource::read(a)?;
    let record = edited_record(&source, a)?;
    let model_config = RigModelConfig::default();
    let rate = match (&source, a.table_rate) {
        (_, Some(r)) => r,
        (ReplaySource::Stroke(t), None) => t.rate_hz,
        (ReplaySource::Log(_), None) => 1000,
    };
    let plan = plan(
        &record,
        rate,
        model_config.tick_hz,
        params.robot.motor_mass_kg,
        params.robot.gravity_m_s2,
        params.drive.peak_force_n,
    )
    .map_err(|e| CliError::input(format!("{}: {}", source_path(a).display(), e.message)))?;
    let view = start_live(&a.live)?;
    let staged = StagedDir::create(&a.out)?;
    let mut robot = robot_fixture(
        a.target.host_plays_the_rig(),
        &params,
        a.rig.model(),
        plan.table.samples_m[0],
        model_config,
    )?;
    let mut link = a.target.open_with_load(
        &model_config,
        Some(VirtualLoad::Robot {
            params: params.clone(),
            model: a.rig.model(),
            p0_m: plan.table.samples_m[0],
        }),
    )?;
    let name = link.name();
    bring_to_idle(link.as_mut())
        .and_then(|()| upload(link.as_mut(), &plan))
        .map_err(|e| link_failed(&name, "the replay upload", e))?;
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
    let (run_result, live) = run_program_live(
        view,
        "replay",
        link.as_mut(),
        robot.as_mut().map(|r| r as &mut dyn Fixture),
        &program,
        None,
        model_config.metres_per_count,
    );
    let run = run_result.map_err(|e| link_failed(&name, "the replay", e))?;

    let mpc = model_config.metres_per_count;
    let (mut worst, mut sum2, mut n) = (0.0f64, 0.0f64, 0usize);
    if let Some(start) = start_index(&run.samples) {
        let t0 = run.samples[start].tick;
        let hz = f64::from(model_config.tick_hz);
        for s in &run.samples[start..] {
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
            let e = (s.encoder_count as f64 * mpc - target).abs();
            worst = worst.max(e);
            sum2 += e * e;
            n += 1;
        }
    }
    let log = samples_log(
        &run.samples,
        model_config.tick_hz,
        mpc,
        firmware_name(&name),
        format!(
            "sandjumper rig replay {} ({name})",
            source_path(a).display()
        ),
        |m| {
            let (jump, phi) = match &source {
                ReplaySource::Log(log) => (log.meta.jump.clone(), log.meta.phi),
                ReplaySource::Stroke(_) => (None, None),
            };
            m.jump = jump;
            m.phi = if a.target.is_simulated() {
                Some(params.sand.packing_fraction)
            } else {
                phi
            };
            m.extra
                .push(("replay_of".into(), source_path(a).display().to_string()));
            m.extra.push(("replay_scale".into(), a.scale.to_string()));
            m.extra
                .push(("replay_time_stretch".into(), a.time_stretch.to_string()));
            m.extra
                .push(("replay_checksum".into(), format!("{:#010x}", plan.checksum)));
        },
    )?;
    let report = ReplayReport {
        link: name.clone(),
        source_log: source_path(a).display().to_string(),
        scale: a.scale,
        time_stretch: a.time_stretch,
        clip_s: a.clip.map(|c| [c.start_s, c.end_s]),
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
        reproduction_error_rms_m: if n > 0 { (sum2 / n as f64).sqrt() } else { 0.0 },
        simulated_jump_height_m: robot
            .as_ref()
            .map(|r| r.plant().summary().jump_height_m)
            .or(run.report.simulated_jump_height_m),
        wall_time_s: run.wall_time_s,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary as JSON: {e}")))?;
    staged.write_text("table.csv", &table_csv(&plan))?;
    let title = format!("rig replay of {} through {name}", source_path(a).display());
    let fig = motion_figure(&run.samples, model_config.tick_hz, mpc, title);
    let dir = write_run_files(staged, &log, &params, &json, &fig, "replay", a.mcap)?;
    if a.json {
        println!("{json}");
    } else {
        println!(
            "rig replay through {name}: {} table samples at {} Hz (checksum {} verified), {}; \
             reproduction error max {:.3} mm, rms {:.3} mm",
            report.table_samples,
            report.table_rate_hz,
            report.checksum,
            if report.completed {
                "completed"
            } else {
                "NOT completed"
            },
            1e3 * report.reproduction_error_max_m,
            1e3 * report.reproduction_error_rms_m
        );
    }
    let result = conclude("replay", report.completed, &report.faults, &dir, a.json);
    crate::live::finish(live, &result);
    result
}
