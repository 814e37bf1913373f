//! `rig jump`: configure, arm and run one sine jump (docs/model.md section 2) on the
//! controller; its acquisition log, the parameters, a summary and a figure.

use std::fmt;
use std::path::PathBuf;

use serde::Serialize;

use sandjumper_acqlog::AcqLog;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_imaging::render::CameraModel;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::plot::lines::LineFigure;
use sandjumper_output::{Progress, StagedDir};

use super::output::{
    FaultEntry, fault_entries, firmware_name, max_tracking_error_m, motion_figure, robot_fixture,
    samples_log, write_run_files,
};
use super::session::{Fixture, Program};
use super::target::Target;
use super::watched::{completed_cleanly, run_watched};
use crate::error::{RigError, to_json};
use crate::hil::rig_model::{RigModel, RigModelConfig};
use crate::hil::run::{HilSpec, trajectory};
use crate::hil::virtual_board::VirtualLoad;
use crate::watch::RunWatch;

/// `rig jump`: the jump and the rig it runs on.
#[derive(Clone, Debug)]
pub struct JumpRequest {
    /// The controller.
    pub target: Target,
    /// Jump kind.
    pub kind: JumpKind,
    /// Forcing frequency f of the one-cycle sine, Hz.
    pub freq_hz: f64,
    /// Delay of the delayed stutter, s (needed with [`JumpKind::DelayedStutter`]).
    pub tau_s: Option<f64>,
    /// Camera frame rate, frames/s (0 none; default 200).
    pub camera_fps: u32,
    /// Ground model of the simulated sand (sil/pil/f407; default eq4).
    pub model: ModelName,
    /// The parameters (the simulated rig's, and the amplitude the controller runs).
    pub params: Params,
    /// The simulated rod camera (sil/pil), whose frames [`JumpOutcome::write`] renders.
    pub camera: CameraModel,
}

impl JumpRequest {
    /// A jump of `kind` at `freq_hz` on `target`: no delay, 200 frames/s, eq4, the phi = 0.57
    /// preset, the default camera.
    pub fn new(target: Target, kind: JumpKind, freq_hz: f64) -> Self {
        Self {
            target,
            kind,
            freq_hz,
            tau_s: None,
            camera_fps: 200,
            model: ModelName::Eq4,
            params: Params::default(),
            camera: CameraModel::default(),
        }
    }

    /// The jump as the loop runs it.
    pub fn spec(&self) -> HilSpec {
        let mut spec = HilSpec::new(
            self.kind,
            self.freq_hz,
            self.tau_s.unwrap_or(0.0),
            self.model,
        );
        spec.camera_fps = self.camera_fps;
        spec
    }

    /// The trajectory exists for these parameters (the words of its refusal otherwise).
    pub fn validate(&self) -> Result<(), RigError> {
        trajectory(&self.params, &self.spec())
            .map(|_| ())
            .map_err(|e| RigError::input(e.to_string()))
    }
}

/// `summary.json` of `rig jump` (the serialised fields), and what its folder holds.
#[derive(Serialize)]
pub struct JumpOutcome {
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
    /// Jump height of the simulated rig (sil/pil/f407), m.
    pub simulated_jump_height_m: Option<f64>,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// Virtual over wall time of the virtual board (`--link f407`), start-up included.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub board_realtime_factor: Option<f64>,
    /// The acquisition log.
    #[serde(skip)]
    pub log: AcqLog,
    /// The parameters run.
    #[serde(skip)]
    pub params: Params,
    /// Commanded vs measured motor position and the force command.
    #[serde(skip)]
    pub figure: LineFigure,
    /// The simulated robot the host played (sil/pil), with its camera frames.
    #[serde(skip)]
    pub robot: Option<RigModel>,
    /// The camera model the frames are rendered with.
    #[serde(skip)]
    pub camera: CameraModel,
    /// Camera frame rate asked for, frames/s.
    #[serde(skip)]
    pub camera_fps: u32,
}

impl fmt::Display for JumpOutcome {
    /// The line `rig jump` prints without `--json` (with its newline).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "rig jump through {}: {} samples ({} dropped), {}, tracking error max {:.2} mm{}",
            self.link,
            self.samples,
            self.dropped_samples,
            if self.completed {
                "completed"
            } else {
                "NOT completed"
            },
            1e3 * self.tracking_error_max_m,
            self.simulated_jump_height_m
                .map_or(String::new(), |h| format!(
                    ", simulated jump height {:.2} mm",
                    1e3 * h
                ))
        )
    }
}

impl JumpOutcome {
    /// `summary.json`'s text (pretty JSON, no newline).
    pub fn json(&self) -> Result<String, RigError> {
        to_json(self, "the summary")
    }

    /// Write acquisition.csv (and with `mcap` acquisition.mcap), params.toml, summary.json,
    /// jump.png and jump.svg (and through a simulated rig with a camera rate frames/) into
    /// `staged`, then commit it; returns the folder.
    pub fn write(&self, staged: StagedDir, mcap: bool) -> Result<PathBuf, RigError> {
        let json = self.json()?;
        if let Some(rig) = self.robot.as_ref().filter(|_| self.camera_fps > 0) {
            crate::hil::camera::write_frames(
                rig.camera_frames(),
                rig.rod_height_history(),
                &self.camera,
                rig.period_s(),
                &staged.file("frames"),
            )
            .map_err(RigError::internal)?;
        }
        write_run_files(
            staged,
            &self.log,
            &self.params,
            &json,
            &self.figure,
            "jump",
            mcap,
        )
    }

    /// Whether the jump completed cleanly, once its folder `dir` is written.
    pub fn check(&self, dir: &std::path::Path) -> Result<(), RigError> {
        completed_cleanly("jump", self.completed, &self.faults, dir)
    }
}

/// Run `rig jump` (see [`run_watched`]).
pub fn run(request: &JumpRequest, progress: &dyn Progress) -> Result<JumpOutcome, RigError> {
    run_watching(request, progress, None)
}

/// [`run`], `watch` shown the run's title and every step.
pub fn run_watching(
    request: &JumpRequest,
    _progress: &dyn Progress,
    watch: Option<&mut dyn RunWatch>,
) -> Result<JumpOutcome, RigError> {
    let params = &request.params;
    let spec = request.spec();
    let traj = trajectory(params, &spec).map_err(|e| RigError::input(e.to_string()))?;
    let model_config = RigModelConfig::default();
    let program = Program::jump(params, &spec, &traj, model_config.tick_hz);
    let p0_m = traj.eval(0.0).position_m;
    let mut robot = robot_fixture(
        request.target.host_plays_the_rig(),
        params,
        spec.model,
        p0_m,
        model_config,
    )?;
    let mut link = request.target.open_with_load(
        &model_config,
        Some(VirtualLoad::Robot {
            params: params.clone(),
            model: spec.model,
            p0_m,
        }),
    )?;
    let name = link.name();
    let record = run_watched(
        watch,
        "jump",
        link.as_mut(),
        robot.as_mut().map(|r| r as &mut dyn Fixture),
        &program,
        Some(&|t: f64| traj.eval(t.clamp(0.0, traj.end_s())).position_m),
        model_config.metres_per_count,
    )
    .map_err(|e| RigError::link(&name, "the jump", e))?;
    let mpc = model_config.metres_per_count;
    let log = samples_log(
        &record.samples,
        model_config.tick_hz,
        mpc,
        firmware_name(&name),
        format!("sandjumper rig jump ({name})"),
        |m| {
            m.jump = Some(spec.log_jump(params.robot.stroke_amplitude_m));
            if request.target.is_simulated() {
                m.phi = Some(params.sand.packing_fraction);
            }
        },
    )?;
    let title = format!(
        "rig jump: {} at f = {} Hz through {name}",
        kind_name(spec.kind),
        spec.freq_hz
    );
    Ok(JumpOutcome {
        link: name,
        kind: kind_name(spec.kind),
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
        figure: motion_figure(&record.samples, model_config.tick_hz, mpc, title),
        log,
        params: params.clone(),
        robot,
        camera: request.camera.clone(),
        camera_fps: request.camera_fps,
    })
}

crate::tool::output::program_outcome!(JumpOutcome);
crate::tool::output::validated_program!(JumpRequest, JumpOutcome, run_watching);
