//! `sandjumper rig intrude`: the slow-intrusion program (docs/model.md section 6; the core's
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

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::intrusion_fixture::IntrusionFixture;
use super::output::{
    FaultEntry, fault_entries, firmware_name, max_tracking_error_m, samples_log, start_index,
    write_run_files,
};
use super::session::{Fixture, Program};
use super::{RigParamArgs, TargetArgs, conclude, link_failed, run_program_live, start_live};
use sandjumper_core::intrusion::{MAX_HOLD_S, MAX_INTRUSION_SPEED_M_S};
use sandjumper_core::{Gains, JumpConfig, SampleRecord, SlowIntrusion, TrajectorySpec};
use sandjumper_model::params::Params;
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_output::plot::lines::{Line, LineFigure, LinePanel, grid_size};
use sandjumper_output::plot::palette;
use sandjumper_rig::hil::rig_model::RigModelConfig;
use sandjumper_rig::hil::virtual_board::VirtualLoad;

fn metres(
    what: &'static str,
    lo: f64,
    hi: f64,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("{what} `{s}` not allowed (allowed: {lo}..={hi})")),
    }
}

/// `rig intrude`.
#[derive(Debug, Clone, Args)]
pub struct IntrudeArgs {
    /// The live view of the run.
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// Motor position p where the foot touches the free surface (the program starts and ends
    /// here), m.
    #[arg(long, value_name = "M", default_value = "-0.02", allow_hyphen_values = true,
          value_parser = metres("start position (m)", -0.025, 0.025))]
    pub start: f64,
    /// First intrusion depth below the surface, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true, default_value = "0.02", value_parser = metres("depth (m)", 0.0, 0.05))]
    pub depth: f64,
    /// How far the rod is pulled back up after the first hold, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true, default_value = "0.005", value_parser = metres("withdrawal (m)", 0.0, 0.05))]
    pub withdraw: f64,
    /// Depth the re-intrusion goes to, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true, default_value = "0.03", value_parser = metres("re-intrusion depth (m)", 0.0, 0.05))]
    pub reintrusion_depth: f64,
    /// Intrusion speed, m/s.
    #[arg(long, value_name = "M/S", allow_negative_numbers = true, default_value = "0.01",
          value_parser = metres("speed (m/s)", 0.0, MAX_INTRUSION_SPEED_M_S))]
    pub speed: f64,
    /// Each hold, s.
    #[arg(long, value_name = "S", allow_negative_numbers = true, default_value = "0.5", value_parser = metres("hold (s)", 0.0, MAX_HOLD_S))]
    pub hold: f64,
    /// Depth bin of the force-vs-depth curves, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true, default_value = "0.00025", value_parser = metres("bin (m)", 1e-6, 0.005))]
    pub bin: f64,
    /// Simulated rig and parameters (masses and force constant to interpret the current).
    #[command(flatten)]
    pub rig: RigParamArgs,
    /// Write intrusion.csv, reintrusion.csv, acquisition.csv, params.toml, summary.json,
    /// intrusion.png and intrusion.svg into DIR.
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

/// `summary.json` of `rig intrude`.
#[derive(Debug, Serialize)]
pub struct IntrudeReport {
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

/// The validated program of `a`.
pub fn program_of(a: &IntrudeArgs) -> Result<SlowIntrusion, CliError> {
    SlowIntrusion::new(
        a.start,
        a.depth,
        a.withdraw,
        a.reintrusion_depth,
        a.speed,
        a.hold,
    )
    .map_err(|e| {
        CliError::input(format!(
            "slow-intrusion program (--start {} --depth {} --withdraw {} --reintrusion-depth {} \
                 --speed {} --hold {}) refused: {e}",
            a.start, a.depth, a.withdraw, a.reintrusion_depth, a.speed, a.hold
        ))
    })
}

/// Run `rig intrude`.
pub fn run(a: &IntrudeArgs) -> Result<(), CliError> {
    let params: Params = a.rig.resolve()?;
    let program_def = program_of(a)?;
    let model_config = RigModelConfig::default();
    let mut fixture = if a.target.host_plays_the_rig() {
        Some(
            IntrusionFixture::new(&params, a.rig.model(), a.start, model_config)
                .map_err(|e| CliError::input(e.to_string()))?,
        )
    } else {
        None
    };
    let moving_mass = params.robot.rod_mass_kg + params.robot.foot_mass_kg;
    let config = JumpConfig {
        gains: intrusion_gains(moving_mass),
        tracking_error_limit_m: 0.01,
        camera_fps: 0,
        ..JumpConfig::new(TrajectorySpec::SlowIntrusion {
            start_m: a.start,
            depth_m: a.depth,
            withdraw_m: a.withdraw,
            reintrusion_depth_m: a.reintrusion_depth,
            speed_m_s: a.speed,
            hold_s: a.hold,
        })
    };
    let program = Program {
        config,
        tick_hz: model_config.tick_hz,
        settle_s: 0.2,
        tail_s: 0.05,
        max_run_s: program_def.end_s() + 5.0,
    };
    let view = start_live(&a.live)?;
    let staged = StagedDir::create(&a.out)?;
    let mut link = a.target.open_with_load(
        &model_config,
        Some(VirtualLoad::Intrusion {
            params: params.clone(),
            model: a.rig.model(),
            surface_p_m: a.start,
        }),
    )?;
    let name = link.name();
    let (run_result, live) = run_program_live(
        view,
        "intrusion",
        link.as_mut(),
        fixture.as_mut().map(|f| f as &mut dyn Fixture),
        &program,
        None,
        model_config.metres_per_count,
    );
    let record = run_result.map_err(|e| link_failed(&name, "the slow intrusion", e))?;

    let mpc = model_config.metres_per_count;
    let Some(start) = start_index(&record.samples) else {
        return Err(CliError::internal(format!(
            "the controller on {name} never started the program (faults: {:?})",
            record.faults
        )));
    };
    let meas = measurements(
        &record.samples,
        start,
        model_config.tick_hz,
        mpc,
        a.start,
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
    let first = binned(&within(0), a.bin, 0.0);
    let re = binned(&within(4), a.bin, a.depth);
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
                .push(("intrusion_start_m".into(), a.start.to_string()));
            if a.target.is_simulated() {
                m.phi = Some(params.sand.packing_fraction);
            }
        },
    )?;
    let report = IntrudeReport {
        link: name.clone(),
        start_m: a.start,
        depth_m: a.depth,
        withdraw_m: a.withdraw,
        reintrusion_depth_m: a.reintrusion_depth,
        speed_m_s: a.speed,
        hold_s: a.hold,
        completed: record.completed,
        faults: fault_entries(&record.faults),
        samples: record.samples.len(),
        dropped_samples: log.meta.dropped_samples,
        tracking_error_max_m: max_tracking_error_m(&record.samples, mpc),
        intrusion_points: first.len(),
        reintrusion_points: re.len(),
        force_at_depth_n: first.last().map(|p| p.force_n),
        wall_time_s: record.wall_time_s,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary as JSON: {e}")))?;
    staged.write_text("intrusion.csv", &curve_csv(&first))?;
    staged.write_text("reintrusion.csv", &curve_csv(&re))?;
    let title = format!(
        "rig intrude through {name}: {} mm at {} mm/s, re-intrusion to {} mm",
        1e3 * a.depth,
        1e3 * a.speed,
        1e3 * a.reintrusion_depth
    );
    let fig = figure(&all, &first, &re, title);
    let dir = write_run_files(staged, &log, &params, &json, &fig, "intrusion", a.mcap)?;
    if a.json {
        println!("{json}");
    } else {
        println!(
            "rig intrude through {name}: {} samples ({} dropped), {}; {} intrusion points, {} \
             re-intrusion points; force at {:.1} mm: {}",
            report.samples,
            report.dropped_samples,
            if report.completed {
                "completed"
            } else {
                "NOT completed"
            },
            report.intrusion_points,
            report.reintrusion_points,
            1e3 * a.depth,
            report
                .force_at_depth_n
                .map_or("n/a".into(), |f| format!("{f:.2} N"))
        );
    }
    let result = conclude("intrusion", report.completed, &report.faults, &dir, a.json);
    crate::live::finish(live, &result);
    result
}
