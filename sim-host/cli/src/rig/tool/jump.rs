//! `sandjumper rig jump`: configure, arm and run one sine jump (docs/model.md section 2) on the
//! controller; write its acquisition log, the parameters, a summary and a figure.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::output::{
    FaultEntry, fault_entries, firmware_name, max_tracking_error_m, motion_figure, robot_fixture,
    samples_log, write_run_files,
};
use super::session::{Fixture, Program};
use super::{RigParamArgs, TargetArgs, conclude, link_failed, run_program_live, start_live};
use crate::command::args::{KindArg, parse_freq, parse_tau};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_rig::hil::rig_model::RigModelConfig;
use sandjumper_rig::hil::run::{HilSpec, trajectory};
use sandjumper_rig::hil::virtual_board::VirtualLoad;

/// `rig jump`.
#[derive(Debug, Clone, Args)]
pub struct JumpArgs {
    /// The live view of the run.
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// Jump kind.
    #[arg(long, value_enum)]
    pub kind: KindArg,
    /// Forcing frequency f of the one-cycle sine, Hz.
    #[arg(long, value_name = "HZ", value_parser = parse_freq)]
    pub freq: f64,
    /// Delay of the delayed stutter, s (required with --kind delayed).
    #[arg(long, value_name = "S", value_parser = parse_tau, required_if_eq("kind", "delayed"))]
    pub tau: Option<f64>,
    /// Camera frame rate, frames/s (200 rod tracking, 500 PIV; 0 none).
    #[arg(long, value_name = "FPS", default_value = "200", value_parser = clap::value_parser!(u32).range(0..=5000))]
    pub camera_fps: u32,
    /// Simulated rig and parameters.
    #[command(flatten)]
    pub rig: RigParamArgs,
    /// The simulated rod camera (TOML; see `hil --camera`), for --link sil|pil.
    #[arg(long, value_name = "FILE.toml")]
    pub camera: Option<PathBuf>,
    /// Write acquisition.csv, params.toml, summary.json, jump.png and jump.svg into DIR
    /// (and, through a simulated rig with a camera rate, frames/: the rendered rod-camera
    /// frames and camera.toml).
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

/// `summary.json` of `rig jump`.
#[derive(Debug, Serialize)]
pub struct JumpReport {
    /// The link.
    pub link: String,
    /// `single`, `stutter` or `delayed`.
    pub kind: &'static str,
    /// Forcing frequency, Hz.
    pub freq_hz: f64,
    /// Delay, s.
    pub tau_s: f64,
    /// Stroke amplitude, m.
    pub amplitude_m: f64,
    /// The controller finished the trajectory (reached Done).
    pub completed: bool,
    /// Faults reported.
    pub faults: Vec<FaultEntry>,
    /// Sample records received.
    pub samples: usize,
    /// Sample records lost (sequence gaps).
    pub dropped_samples: u64,
    /// Camera frames triggered.
    pub camera_frames: usize,
    /// Largest |p_cmd - p| during the trajectory, m.
    pub tracking_error_max_m: f64,
    /// Jump height of the simulated rig (sil/pil), m.
    pub simulated_jump_height_m: Option<f64>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// Virtual over wall time of the virtual board (`--link f407`), start-up included.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub board_realtime_factor: Option<f64>,
}

/// Run `rig jump`.
pub fn run(a: &JumpArgs) -> Result<(), CliError> {
    let params = a.rig.resolve()?;
    let kind: JumpKind = a.kind.into();
    let mut spec = HilSpec::new(kind, a.freq, a.tau.unwrap_or(0.0), a.rig.model());
    spec.camera_fps = a.camera_fps;
    let traj = trajectory(&params, &spec).map_err(|e| CliError::input(e.to_string()))?;
    let model_config = RigModelConfig::default();
    let program = Program::jump(&params, &spec, &traj, model_config.tick_hz);
    let camera = crate::rig::hil::command::read_camera(a.camera.as_deref())?;
    let view = start_live(&a.live)?;
    let staged = StagedDir::create(&a.out)?;
    let mut robot = robot_fixture(
        a.target.host_plays_the_rig(),
        &params,
        spec.model,
        traj.eval(0.0).position_m,
        model_config,
    )?;
    let mut link = a.target.open_with_load(
        &model_config,
        Some(VirtualLoad::Robot {
            params: params.clone(),
            model: spec.model,
            p0_m: traj.eval(0.0).position_m,
        }),
    )?;
    let name = link.name();
    let (run_result, live) = run_program_live(
        view,
        "jump",
        link.as_mut(),
        robot.as_mut().map(|r| r as &mut dyn Fixture),
        &program,
        Some(&|t: f64| traj.eval(t.clamp(0.0, traj.end_s())).position_m),
        model_config.metres_per_count,
    );
    let record = run_result.map_err(|e| link_failed(&name, "the jump", e))?;

    let mpc = model_config.metres_per_count;
    let phi = params.sand.packing_fraction;
    let log = samples_log(
        &record.samples,
        model_config.tick_hz,
        mpc,
        firmware_name(&name),
        format!("sandjumper rig jump ({name})"),
        |m| {
            m.jump = Some(spec.log_jump(params.robot.stroke_amplitude_m));
            if a.target.is_simulated() {
                m.phi = Some(phi);
            }
        },
    )?;
    let report = JumpReport {
        link: name.clone(),
        kind: kind_name(kind),
        freq_hz: spec.freq_hz,
        tau_s: spec.tau_s,
        amplitude_m: params.robot.stroke_amplitude_m,
        completed: record.completed,
        faults: fault_entries(&record.faults),
        samples: record.samples.len(),
        dropped_samples: log.meta.dropped_samples,
        camera_frames: record
            .samples
            .iter()
            .filter(|s| s.camera_frame.is_some())
            .count(),
        tracking_error_max_m: max_tracking_error_m(&record.samples, mpc),
        simulated_jump_height_m: robot
            .as_ref()
            .map(|r| r.plant().summary().jump_height_m)
            .or(record.report.simulated_jump_height_m),
        wall_time_s: record.wall_time_s,
        board_realtime_factor: record.report.board_realtime_factor,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary as JSON: {e}")))?;
    let title = format!(
        "rig jump: {} at f = {} Hz through {name}",
        kind_name(kind),
        spec.freq_hz
    );
    if let Some(rig) = robot.as_ref().filter(|_| a.camera_fps > 0) {
        sandjumper_rig::hil::camera::write_frames(
            rig.camera_frames(),
            rig.rod_height_history(),
            &camera,
            rig.period_s(),
            &staged.file("frames"),
        )
        .map_err(CliError::internal)?;
    }
    let fig = motion_figure(&record.samples, model_config.tick_hz, mpc, title);
    let dir = write_run_files(staged, &log, &params, &json, &fig, "jump", a.mcap)?;
    if a.json {
        println!("{json}");
    } else {
        println!(
            "rig jump through {name}: {} samples ({} dropped), {}, tracking error max {:.2} mm{}",
            report.samples,
            report.dropped_samples,
            if report.completed {
                "completed"
            } else {
                "NOT completed"
            },
            1e3 * report.tracking_error_max_m,
            report
                .simulated_jump_height_m
                .map_or(String::new(), |h| format!(
                    ", simulated jump height {:.2} mm",
                    1e3 * h
                ))
        );
    }
    let result = conclude("jump", report.completed, &report.faults, &dir, a.json);
    crate::live::finish(live, &result);
    result
}
