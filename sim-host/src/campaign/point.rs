//! One point of a campaign: prepare the bed, jump through the link, save the acquisition
//! log and the camera's frames in the point's folder, track the rod for the measured jump
//! height, replay the encoder log for the predicted one.

use std::path::Path;

use serde::Serialize;

use super::bed::SimulatedBed;
use super::file::CampaignFile;
use super::journal::{Event, Journal};
use super::plan::Point;
use super::prepare::{Preparation, prepare};
use super::records::ResultRow;
use crate::acqlog::{AcqLog, ReadOptions};
use crate::imaging::command::log_clock;
use crate::imaging::render::CameraModel;
use crate::imaging::sequence::ImageSequence;
use crate::imaging::track::{TrackSpec, track_sequence};
use crate::model::params::{PRESET_PHI_MAX, PRESET_PHI_MIN};
use crate::model::trajectory::parse_kind;
use crate::rig::hil::camera::{heights_by_period, write_frames};
use crate::rig::hil::command::{LinkArg, open_link};
use crate::rig::hil::log::acquisition_log;
use crate::rig::hil::{HilSpec, RigModelConfig, run_jump};
use crate::study::replay::{DEFAULT_WINDOW_S, replay_log};
use crate::{ModelName, Params, SimOptions};
use sandjumper_core::bed::BedInputs;

/// How to reach the controller.
#[derive(Clone, Debug)]
pub struct Link {
    /// The link.
    pub arg: LinkArg,
    /// Firmware image (PIL).
    pub firmware: std::path::PathBuf,
}

/// A point's `point.json`.
#[derive(Serialize)]
struct PointRecord<'a> {
    point: &'a Point,
    preparation: &'a Preparation,
    phi_used_by_the_plant: f64,
    plant_jump_height_m: f64,
    measured_jump_height_m: Option<f64>,
    predicted_jump_height_m: Option<f64>,
    camera_frames: usize,
    frames_lost: u32,
    faults: Vec<&'static str>,
    track_frames_flagged: Option<usize>,
}

/// Run `point` (from fluidization), journalling each phase; returns its row.
pub fn run_point(
    f: &CampaignFile,
    point: &Point,
    link: &Link,
    dir: &Path,
    journal: &mut Journal,
    on_phase: &mut dyn FnMut(&str),
) -> Result<ResultRow, String> {
    let b = &f.bed;
    journal.append(Event::PointStarted { point: point.index })?;
    on_phase("bed");
    let mut bed = SimulatedBed::new(
        &f.simulated_bed,
        b.grain_mass_kg,
        b.grain_density_kg_m3,
        b.area_m2,
        point.seed(f.seed),
    );
    let prep = prepare(&mut bed, b, point.target_phi)?;
    journal.append(Event::BedPrepared {
        point: point.index,
        preparation: prep.clone(),
    })?;
    let mut row = ResultRow {
        point: point.index,
        repeat: point.repeat,
        kind: point.kind.clone(),
        freq_hz: point.freq_hz,
        tau_s: point.tau_s,
        target_phi: point.target_phi,
        achieved_phi: prep.achieved_phi,
        attempts: prep.attempts,
        fluidizations: prep.fluidizations,
        doses: prep.doses,
        status: "done".into(),
        measured_jump_height_m: None,
        frames_flagged: None,
        predicted_jump_height_m: None,
        plant_jump_height_m: None,
        faults: String::new(),
        folder: point.folder(),
    };
    if !prep.ok {
        row.status = "bed-not-prepared".into();
        row.faults = prep.failure.clone().unwrap_or_default();
        row.folder = String::new();
        return Ok(row);
    }

    // The jump, on sand at the achieved phi (the presets interpolated there).
    on_phase("jump");
    let phi = prep.achieved_phi.clamp(PRESET_PHI_MIN, PRESET_PHI_MAX);
    let params = Params::preset(phi).map_err(|e| e.to_string())?;
    let model: ModelName = f.model.parse().map_err(|e| format!("{e}"))?;
    let kind = parse_kind(&point.kind).ok_or_else(|| format!("kind `{}`", point.kind))?;
    let mut spec = HilSpec::new(kind, point.freq_hz, point.tau_s, model);
    spec.gain_lowering = f.grid.gain_lowering.map(HilSpec::gain_lowering_factor);
    spec.camera_fps = f.camera.fps;
    // The rig has the apparatus: the lift is down in the bed and (the preparation over)
    // blower and shaker are off, so the controller's interlocks let it arm.
    spec.bed = Some(BedInputs {
        lift_down_limit: true,
        ..BedInputs::default()
    });
    let model_config = RigModelConfig::default();
    let mut l = open_link(&link.arg, &model_config, &link.firmware).map_err(|e| e.message)?;
    let outcome = run_jump(&params, &spec, model_config, l.as_mut()).map_err(|e| {
        format!(
            "point {}: the jump through the link failed: {e}",
            point.index
        )
    })?;
    let target = dir.join(point.folder());
    let staging = dir.join(format!("{}.partial", point.folder()));
    for d in [&target, &staging] {
        if d.exists() {
            std::fs::remove_dir_all(d).map_err(|e| format!("cannot clear {}: {e}", d.display()))?;
        }
    }
    std::fs::create_dir_all(&staging)
        .map_err(|e| format!("cannot create {}: {e}", staging.display()))?;
    let log = acquisition_log(
        &outcome,
        &spec,
        model_config.tick_hz,
        model_config.metres_per_count,
        params.robot.stroke_amplitude_m,
        phi,
    );
    log.write_file(&staging.join("acquisition.csv"))
        .map_err(|e| format!("cannot write the acquisition log: {e}"))?;
    let camera = CameraModel::default();
    if f.camera.fps > 0 {
        write_frames(
            &outcome.camera_frames,
            &heights_by_period(&outcome),
            &camera,
            1.0 / f64::from(model_config.tick_hz),
            &staging.join("frames"),
        )?;
    }
    journal.append(Event::Jumped { point: point.index })?;

    // Analyses.
    on_phase("analyse");
    let log = AcqLog::read_file(&staging.join("acquisition.csv"), &ReadOptions::default())
        .map_err(|e| format!("cannot read back the acquisition log: {e}"))?;
    let mut flagged = None;
    if f.analysis.track {
        let seq = ImageSequence::open(staging.join("frames").to_str().unwrap_or_default())
            .map_err(|e| format!("point {}: frames: {e}", point.index))?;
        let ts = TrackSpec {
            exposure_s: camera.exposure_s,
            ..TrackSpec::new(camera.m_per_px)
        };
        match track_sequence(&seq, &ts, &log_clock(&log)) {
            Ok(r) => {
                row.measured_jump_height_m = Some(r.apex.jump_height_m);
                flagged = Some(r.frames_flagged());
                row.frames_flagged = flagged;
            }
            Err(e) => row.faults.push_str(&format!("tracking failed: {e};")),
        }
    }
    if f.analysis.replay {
        let r = replay_log(
            &log,
            &params,
            model,
            DEFAULT_WINDOW_S,
            &SimOptions::default(),
        )
        .map_err(|e| format!("point {}: replay: {e}", point.index))?;
        row.predicted_jump_height_m = Some(r.outcome.summary.jump_height_m);
    }
    row.plant_jump_height_m = Some(outcome.summary.jump_height_m);
    let faults: Vec<&'static str> = outcome.faults.iter().map(|f| f.code.name()).collect();
    if !faults.is_empty() {
        row.status = "faulted".into();
        row.faults.push_str(&faults.join(";"));
    }
    let rec = PointRecord {
        point,
        preparation: &prep,
        phi_used_by_the_plant: phi,
        plant_jump_height_m: outcome.summary.jump_height_m,
        measured_jump_height_m: row.measured_jump_height_m,
        predicted_jump_height_m: row.predicted_jump_height_m,
        camera_frames: outcome.camera_frames.len(),
        frames_lost: outcome.frames_lost,
        faults,
        track_frames_flagged: flagged,
    };
    let json = serde_json::to_string_pretty(&rec).map_err(|e| e.to_string())?;
    std::fs::write(staging.join("point.json"), json + "\n")
        .map_err(|e| format!("cannot write point.json: {e}"))?;
    std::fs::write(staging.join("params.toml"), params.to_toml())
        .map_err(|e| format!("cannot write params.toml: {e}"))?;
    std::fs::rename(&staging, &target)
        .map_err(|e| format!("cannot finish {}: {e}", target.display()))?;
    journal.append(Event::Analysed { point: point.index })?;
    Ok(row)
}
