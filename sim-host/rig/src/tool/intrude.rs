//! `rig intrude`: the slow-intrusion program (docs/model.md section 6; the core's
//! [`sandjumper_core::SlowIntrusion`]) with the motor clamped to the bed: intrude, hold,
//! withdraw part way, hold, re-intrude deeper, hold, withdraw. The paper's `F_p(z)`
//! measurement.
//!
//! - Depth from the encoder: `z = p - start` (the foot touches the free surface at the
//!   program's start position).
//! - Force on the sand from the motor current: `F = K_f i + m g` with `m` the moving mass
//!   (rod and foot; quasi-static: the program's 0.05 m/s at most makes `m p''` negligible).
//!   Without a current reading, the force command stands in for `K_f i`.
//! - `intrusion.csv` (first intrusion, from the surface) and `reintrusion.csv` (the
//!   re-intrusion beyond the first depth, where the foot meets its old hole's bottom): columns
//!   `depth_m,force_n`, averaged in depth bins of `--bin` so depth strictly increases: the
//!   input of `sandjumper fit intrusion` (`--first` / `--reintrusion`).

use std::fmt::{self, Write as _};
use std::path::{Path, PathBuf};

use serde::Serialize;

use sandjumper_acqlog::AcqLog;
use sandjumper_core::{Gains, JumpConfig, SampleRecord, SlowIntrusion, TrajectorySpec};
use sandjumper_model::params::{ModelName, Params};
use sandjumper_output::parse::number_within;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::palette;
use sandjumper_output::{Progress, StagedDir};

use super::intrusion_fixture::IntrusionFixture;
use super::output::{
    FaultEntry, fault_entries, firmware_name, max_tracking_error_m, samples_log, start_index,
    write_run_files,
};
use super::session::{Fixture, Program};
use super::target::Target;
use super::watched::{completed_cleanly, run_watched};
use crate::error::{RigError, to_json};
use crate::hil::rig_model::RigModelConfig;
use crate::hil::virtual_board::VirtualLoad;
use crate::watch::RunWatch;

/// `rig intrude`: the slow-intrusion program and the rig it runs on.
#[derive(Clone, Debug)]
pub struct IntrudeRequest {
    /// The controller.
    pub target: Target,
    /// Motor position p where the foot touches the free surface (start and end), m
    /// (default -0.02).
    pub start_m: f64,
    /// First intrusion depth below the surface, m (default 0.02).
    pub depth_m: f64,
    /// How far the rod is pulled back up after the first hold, m (default 0.005).
    pub withdraw_m: f64,
    /// Depth the re-intrusion goes to, m (default 0.03).
    pub reintrusion_depth_m: f64,
    /// Intrusion speed, m/s (default 0.01).
    pub speed_m_s: f64,
    /// Each hold, s (default 0.5).
    pub hold_s: f64,
    /// Depth bin of the force-vs-depth curves, m (default 0.00025).
    pub bin_m: f64,
    /// Ground model of the simulated sand (default eq4).
    pub model: ModelName,
    /// The parameters (masses and force constant to interpret the current).
    pub params: Params,
}

impl Default for IntrudeRequest {
    fn default() -> Self {
        Self {
            target: Target::default(),
            start_m: -0.02,
            depth_m: 0.02,
            withdraw_m: 0.005,
            reintrusion_depth_m: 0.03,
            speed_m_s: 0.01,
            hold_s: 0.5,
            bin_m: 0.00025,
            model: ModelName::Eq4,
            params: Params::default(),
        }
    }
}

impl IntrudeRequest {
    /// The validated program (the core's refusal, with the settings, otherwise).
    pub fn program(&self) -> Result<SlowIntrusion, RigError> {
        SlowIntrusion::new(
            self.start_m,
            self.depth_m,
            self.withdraw_m,
            self.reintrusion_depth_m,
            self.speed_m_s,
            self.hold_s,
        )
        .map_err(|e| {
            RigError::input(format!(
                "slow-intrusion program (--start {} --depth {} --withdraw {} --reintrusion-depth {} \
                 --speed {} --hold {}) refused: {e}",
                self.start_m,
                self.depth_m,
                self.withdraw_m,
                self.reintrusion_depth_m,
                self.speed_m_s,
                self.hold_s
            ))
        })
    }

    /// [`IntrudeRequest::program`]'s check.
    pub fn validate(&self) -> Result<(), RigError> {
        self.program().map(|_| ())
    }
}

/// Gains for the clamped fixture: the rod and foot alone (0.155 kg) and an integrator, so the
/// sand's tens of newtons do not leave a steady tracking error (PID stable: `kd kp > m ki`).
pub fn intrusion_gains(moving_mass_kg: f64) -> Gains {
    Gains {
        kp_n_per_m: 11_000.0,
        kd_n_s_per_m: 70.0,
        ki_n_per_m_s: 200_000.0,
        integral_limit_n: 250.0,
        feedforward_mass_kg: moving_mass_kg as f32,
    }
}

/// One point of a force-vs-depth curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CurvePoint {
    /// Depth below the free surface, m.
    pub depth_m: f64,
    /// Force on the sand, N.
    pub force_n: f64,
}

/// `(depth, force)` of every sample, with its time since the trajectory's start.
fn measurements(
    samples: &[SampleRecord],
    start: usize,
    tick_hz: u32,
    metres_per_count: f64,
    surface_m: f64,
    k_f: f64,
    weight_n: f64,
) -> Vec<(f64, CurvePoint)> {
    let t0 = samples[start].tick;
    samples[start..]
        .iter()
        .map(|s| {
            let motor_n = match s.current_a {
                Some(i) => k_f * f64::from(i),
                None => f64::from(s.force_n),
            };
            (
                f64::from(s.tick.wrapping_sub(t0)) / f64::from(tick_hz),
                CurvePoint {
                    depth_m: s.encoder_count as f64 * metres_per_count - surface_m,
                    force_n: motor_n + weight_n,
                },
            )
        })
        .collect()
}

/// Mean depth and force per depth bin, bins with centres from `from_m` on, depth increasing.
fn binned(points: &[CurvePoint], bin_m: f64, from_m: f64) -> Vec<CurvePoint> {
    let mut bins: std::collections::BTreeMap<i64, (f64, f64, u32)> = Default::default();
    for p in points {
        let k = (p.depth_m / bin_m).floor() as i64;
        if (k as f64 + 0.5) * bin_m < from_m {
            continue;
        }
        let e = bins.entry(k).or_insert((0.0, 0.0, 0));
        e.0 += p.depth_m;
        e.1 += p.force_n;
        e.2 += 1;
    }
    bins.values()
        .map(|&(z, f, n)| CurvePoint {
            depth_m: z / f64::from(n),
            force_n: f / f64::from(n),
        })
        .filter(|p| p.depth_m > 0.0)
        .collect()
}

fn curve_csv(points: &[CurvePoint]) -> String {
    let mut s = String::from("depth_m,force_n\n");
    for p in points {
        let _ = writeln!(s, "{},{}", p.depth_m, p.force_n);
    }
    s
}

/// `summary.json` of `rig intrude` (the serialised fields), and what its folder holds.
#[derive(Serialize)]
pub struct IntrudeOutcome {
    /// The link.
    pub link: String,
    /// Program: start (surface) position, m.
    pub start_m: f64,
    /// First intrusion depth, m.
    pub depth_m: f64,
    /// Withdrawal, m.
    pub withdraw_m: f64,
    /// Re-intrusion depth, m.
    pub reintrusion_depth_m: f64,
    /// Speed, m/s.
    pub speed_m_s: f64,
    /// Hold, s.
    pub hold_s: f64,
    /// The controller finished the program.
    pub completed: bool,
    /// Faults reported.
    pub faults: Vec<FaultEntry>,
    /// Sample records received.
    pub samples: usize,
    /// Sample records lost.
    pub dropped_samples: u64,
    /// Largest |p_cmd - p|, m.
    pub tracking_error_max_m: f64,
    /// Points in intrusion.csv.
    pub intrusion_points: usize,
    /// Points in reintrusion.csv.
    pub reintrusion_points: usize,
    /// Force at the deepest point of the first intrusion, N.
    pub force_at_depth_n: Option<f64>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// The first intrusion's force-vs-depth curve (intrusion.csv).
    #[serde(skip)]
    pub intrusion: Vec<CurvePoint>,
    /// The re-intrusion's (reintrusion.csv).
    #[serde(skip)]
    pub reintrusion: Vec<CurvePoint>,
    /// The acquisition log.
    #[serde(skip)]
    pub log: AcqLog,
    /// The parameters run.
    #[serde(skip)]
    pub params: Params,
    /// Force against depth.
    #[serde(skip)]
    pub figure: LineFigure,
}

impl fmt::Display for IntrudeOutcome {
    /// The line `rig intrude` prints without `--json` (with its newline).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "rig intrude through {}: {} samples ({} dropped), {}; {} intrusion points, {} \
             re-intrusion points; force at {:.1} mm: {}",
            self.link,
            self.samples,
            self.dropped_samples,
            if self.completed {
                "completed"
            } else {
                "NOT completed"
            },
            self.intrusion_points,
            self.reintrusion_points,
            1e3 * self.depth_m,
            self.force_at_depth_n
                .map_or("n/a".into(), |f| format!("{f:.2} N"))
        )
    }
}

impl IntrudeOutcome {
    /// `summary.json`'s text (pretty JSON, no newline).
    pub fn json(&self) -> Result<String, RigError> {
        to_json(self, "the summary")
    }

    /// Write intrusion.csv, reintrusion.csv, acquisition.csv (and with `mcap`
    /// acquisition.mcap), params.toml, summary.json, intrusion.png and intrusion.svg into
    /// `staged`, then commit it.
    pub fn write(&self, staged: StagedDir, mcap: bool) -> Result<PathBuf, RigError> {
        let json = self.json()?;
        staged.write_text("intrusion.csv", &curve_csv(&self.intrusion))?;
        staged.write_text("reintrusion.csv", &curve_csv(&self.reintrusion))?;
        write_run_files(
            staged,
            &self.log,
            &self.params,
            &json,
            &self.figure,
            "intrusion",
            mcap,
        )
    }

    /// Whether the program completed cleanly, once its folder `dir` is written.
    pub fn check(&self, dir: &Path) -> Result<(), RigError> {
        completed_cleanly("intrusion", self.completed, &self.faults, dir)
    }
}

fn figure(
    all: &[CurvePoint],
    first: &[CurvePoint],
    re: &[CurvePoint],
    title: String,
) -> LineFigure {
    let step = (all.len() / 4000).max(1);
    let mm = |ps: &[CurvePoint], step: usize| -> Vec<(f64, f64)> {
        ps.iter()
            .step_by(step)
            .map(|p| (1e3 * p.depth_m, p.force_n))
            .collect()
    };
    let line = |label: &str, i: usize, dashed: bool, markers: bool, points| Line {
        label: label.into(),
        points,
        color: palette(i),
        dashed,
        markers,
    };
    let panels = vec![LinePanel {
        caption: "penetration force vs depth (force from the motor current)".into(),
        x_desc: "depth below the free surface z (mm)".into(),
        y_desc: "force on the sand (N)".into(),
        lines: vec![
            line("whole program", 2, true, false, mm(all, step)),
            line("first intrusion", 0, false, true, mm(first, 1)),
            line("re-intrusion", 1, false, true, mm(re, 1)),
        ],
        y_from_zero: true,
    }];
    LineFigure {
        title,
        size: grid_size(panels.len()),
        panels,
    }
}

/// Run `rig intrude`.
pub fn run(request: &IntrudeRequest, progress: &dyn Progress) -> Result<IntrudeOutcome, RigError> {
    run_watching(request, progress, None)
}

/// The controller's configuration of the program: the clamped fixture's gains, a 10 mm
/// tracking bound, no camera.
fn intrusion_config(request: &IntrudeRequest, moving_mass_kg: f64) -> JumpConfig {
    JumpConfig {
        gains: intrusion_gains(moving_mass_kg),
        tracking_error_limit_m: 0.01,
        camera_fps: 0,
        ..JumpConfig::new(TrajectorySpec::SlowIntrusion {
            start_m: request.start_m,
            depth_m: request.depth_m,
            withdraw_m: request.withdraw_m,
            reintrusion_depth_m: request.reintrusion_depth_m,
            speed_m_s: request.speed_m_s,
            hold_s: request.hold_s,
        })
    }
}

/// [`run`], `watch` shown the run's title and every step.
pub fn run_watching(
    request: &IntrudeRequest,
    _progress: &dyn Progress,
    watch: Option<&mut dyn RunWatch>,
) -> Result<IntrudeOutcome, RigError> {
    let params = &request.params;
    let program_def = request.program()?;
    let model_config = RigModelConfig::default();
    let mut fixture = if request.target.host_plays_the_rig() {
        Some(
            IntrusionFixture::new(params, request.model, request.start_m, model_config)
                .map_err(|e| RigError::input(e.to_string()))?,
        )
    } else {
        None
    };
    let moving_mass = params.robot.rod_mass_kg + params.robot.foot_mass_kg;
    let program = Program {
        config: intrusion_config(request, moving_mass),
        tick_hz: model_config.tick_hz,
        settle_s: 0.2,
        tail_s: 0.05,
        max_run_s: program_def.end_s() + 5.0,
    };
    let mut link = request.target.open_with_load(
        &model_config,
        Some(VirtualLoad::Intrusion {
            params: params.clone(),
            model: request.model,
            surface_p_m: request.start_m,
        }),
    )?;
    let name = link.name();
    let record = run_watched(
        watch,
        "intrusion",
        link.as_mut(),
        fixture.as_mut().map(|f| f as &mut dyn Fixture),
        &program,
        None,
        model_config.metres_per_count,
    )
    .map_err(|e| RigError::link(&name, "the slow intrusion", e))?;
    let mpc = model_config.metres_per_count;
    let Some(start) = start_index(&record.samples) else {
        return Err(RigError::internal(format!(
            "the controller on {name} never started the program (faults: {:?})",
            record.faults
        )));
    };
    let meas = measurements(
        &record.samples,
        start,
        model_config.tick_hz,
        mpc,
        request.start_m,
        params.drive.force_constant_n_a,
        moving_mass * params.robot.gravity_m_s2,
    );
    let segs = program_def.segments();
    let within = |i: usize| {
        let s = segs[i];
        meas.iter()
            .filter(|(t, _)| *t >= s.t0_s && *t < s.t0_s + s.duration_s)
            .map(|(_, p)| *p)
            .collect::<Vec<_>>()
    };
    let first = binned(&within(0), request.bin_m, 0.0);
    let re = binned(&within(4), request.bin_m, request.depth_m);
    let all: Vec<CurvePoint> = meas.iter().map(|(_, p)| *p).collect();
    let log = samples_log(
        &record.samples,
        model_config.tick_hz,
        mpc,
        firmware_name(&name),
        format!("sandjumper rig intrude ({name})"),
        |m| {
            m.extra.push(("program".into(), "slow_intrusion".into()));
            m.extra
                .push(("intrusion_start_m".into(), request.start_m.to_string()));
            if request.target.is_simulated() {
                m.phi = Some(params.sand.packing_fraction);
            }
        },
    )?;
    let title = format!(
        "rig intrude through {name}: {} mm at {} mm/s, re-intrusion to {} mm",
        1e3 * request.depth_m,
        1e3 * request.speed_m_s,
        1e3 * request.reintrusion_depth_m
    );
    Ok(IntrudeOutcome {
        link: name,
        start_m: request.start_m,
        depth_m: request.depth_m,
        withdraw_m: request.withdraw_m,
        reintrusion_depth_m: request.reintrusion_depth_m,
        speed_m_s: request.speed_m_s,
        hold_s: request.hold_s,
        completed: record.completed,
        faults: fault_entries(&record.faults),
        samples: record.samples.len(),
        dropped_samples: log.meta.dropped_samples,
        tracking_error_max_m: max_tracking_error_m(&record.samples, mpc),
        intrusion_points: first.len(),
        reintrusion_points: re.len(),
        force_at_depth_n: first.last().map(|p| p.force_n),
        wall_time_s: record.wall_time_s,
        figure: figure(&all, &first, &re, title),
        intrusion: first,
        reintrusion: re,
        log,
        params: params.clone(),
    })
}

crate::tool::output::program_outcome!(IntrudeOutcome);

/// The value parser of one of the program's lengths, speeds or times: a finite number in
/// `lo..=hi` (its unit `what`'s); `what` names it in the message.
pub fn parse_bounded(
    what: &'static str,
    lo: f64,
    hi: f64,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        number_within(s, |v| (lo..=hi).contains(&v))
            .ok_or_else(|| format!("{what} `{s}` not allowed (allowed: {lo}..={hi})"))
    }
}
crate::tool::output::validated_program!(IntrudeRequest, IntrudeOutcome, run_watching);
