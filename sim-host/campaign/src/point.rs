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
use sandjumper_acqlog::AcqLog;
use sandjumper_core::bed::BedInputs;
use sandjumper_imaging::render::CameraModel;
use sandjumper_imaging::sequence::ImageSequence;
use sandjumper_imaging::track::log_clock;
use sandjumper_imaging::track::{TrackSpec, track_sequence};
use sandjumper_model::params::{PRESET_PHI_MAX, PRESET_PHI_MIN};
use sandjumper_model::trajectory::parse_kind;
use sandjumper_model::{ModelName, Params, SimOptions};
use sandjumper_rig::hil::camera::{heights_by_period, write_frames};
use sandjumper_rig::hil::log::acquisition_log;
use sandjumper_rig::hil::open::{LinkArg, open_link};
use sandjumper_rig::hil::{HilSpec, RigModelConfig, run_jump};
use sandjumper_study::replay::{DEFAULT_WINDOW_S, replay_log};

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
    let mut row = record_preparation(journal, point, &prep)?;
    if !prep.ok {
        return Ok(row);
    }

    // The jump, on sand at the achieved phi (the presets interpolated there).
    on_phase("jump");
    let JumpSetup {
        phi,
        params,
        model,
        mut spec,
    } = jump_setup(f, point, &prep)?;
    // The rig has the apparatus: the lift is down in the bed and (the preparation over)
    // blower and shaker are off, so the controller's interlocks let it arm.
    spec.bed = Some(BedInputs {
        lift_down_limit: true,
        ..BedInputs::default()
    });
    let model_config = RigModelConfig::default();
    let mut l = open_link(&link.arg, &model_config, &link.firmware).map_err(|e| e.to_string())?;
    let outcome = run_jump(&params, &spec, model_config, l.as_mut()).map_err(|e| {
        format!(
            "point {}: the jump through the link failed: {e}",
            point.index
        )
    })?;
    let (target, staging) = fresh_folders(dir, point)?;
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
    let mut flagged = None;
    if f.analysis.track {
        let ts = TrackSpec {
            exposure_s: camera.exposure_s,
            ..TrackSpec::new(camera.m_per_px)
        };
        let (m, fl, err) = track(&staging.join("frames"), &ts, &log);
        (row.measured_jump_height_m, row.frames_flagged, flagged) = (m, fl, fl);
        row.faults.push_str(&err);
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
    finish_folder(&rec, &params, &staging, &target)?;
    journal.append(Event::Analysed { point: point.index })?;
    Ok(row)
}

/// Opens a fresh link to the board (a session ends its link).
pub type Connect<'a> =
    dyn FnMut() -> Result<Box<dyn sandjumper_rig::hil::link::RigLink>, String> + 'a;

/// Run `point` on a real board: the bed prepared through the board's apparatus, the lift
/// lowered, the jump run free on the board's own rig (the rig tool's session), its samples
/// saved as the acquisition log and replayed for the predicted height. No camera frames are
/// collected (the lab's camera writes them elsewhere), so there is no measured height.
pub fn run_point_on_board(
    f: &CampaignFile,
    point: &Point,
    connect: &mut Connect<'_>,
    dir: &Path,
    journal: &mut Journal,
    on_phase: &mut dyn FnMut(&str),
) -> Result<ResultRow, String> {
    use super::board_bed::BoardBed;
    use sandjumper_rig::hil::run::trajectory;
    use sandjumper_rig::tool::output::{firmware_name, samples_log};
    use sandjumper_rig::tool::session::{Program, run_program};

    let b = &f.bed;
    let sensor = b
        .height_sensor
        .ok_or("a campaign on a board needs [bed.height_sensor]")?;
    journal.append(Event::PointStarted { point: point.index })?;
    on_phase("bed");
    let mut link = connect()?;
    let name = link.name();
    let prep = {
        let mut bed = BoardBed::new(link.as_mut(), sensor, b.lift_timeout_s);
        let prep = match prepare(&mut bed, b, point.target_phi) {
            Ok(p) => p,
            Err(e) => {
                bed.all_off();
                return Err(format!("point {}: bed preparation: {e}", point.index));
            }
        };
        bed.all_off();
        if prep.ok {
            bed.lift(false)
                .map_err(|e| format!("point {}: lowering the jumper: {e}", point.index))?;
        }
        prep
    };
    let mut row = record_preparation(journal, point, &prep)?;
    if !prep.ok {
        return Ok(row);
    }

    on_phase("jump");
    let JumpSetup {
        phi,
        params,
        model,
        spec,
    } = jump_setup(f, point, &prep)?;
    let traj = trajectory(&params, &spec).map_err(|e| e.to_string())?;
    let model_config = RigModelConfig::default();
    let program = Program::jump(&params, &spec, &traj, model_config.tick_hz);
    let record = run_program(link.as_mut(), None, &program)
        .map_err(|e| format!("point {}: the jump on {name}: {e}", point.index))?;
    // The session is over: the board's link closes before the frames are collected.
    drop(link);
    let (target, staging) = fresh_folders(dir, point)?;
    let log = samples_log(
        &record.samples,
        model_config.tick_hz,
        model_config.metres_per_count,
        firmware_name(&name),
        format!("sandjumper campaign ({name})"),
        |m| {
            m.jump = Some(spec.log_jump(params.robot.stroke_amplitude_m));
            m.phi = Some(prep.achieved_phi);
        },
    )
    .map_err(|e| e.to_string())?;
    log.write_file(&staging.join("acquisition.csv"))
        .map_err(|e| format!("cannot write the acquisition log: {e}"))?;
    journal.append(Event::Jumped { point: point.index })?;

    let expected_frames = record
        .samples
        .iter()
        .filter(|s| s.camera_frame.is_some())
        .count();
    let mut camera_note = String::new();
    if let Some(capture) = &f.camera.capture_dir {
        on_phase("frames");
        let got = collect_frames(
            capture,
            &staging.join("frames"),
            expected_frames,
            f.camera.capture_timeout_s,
        )?;
        if got < expected_frames {
            camera_note = format!("camera: {got} of {expected_frames} frames;");
        }
    }

    on_phase("analyse");
    let mut flagged = None;
    if f.analysis.track {
        let ts = TrackSpec {
            exposure_s: f.camera.exposure_s,
            ..TrackSpec::new(f.camera.m_per_px)
        };
        let (m, fl, err) = track(&staging.join("frames"), &ts, &log);
        (row.measured_jump_height_m, row.frames_flagged, flagged) = (m, fl, fl);
        camera_note.push_str(&err);
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
    row.faults.push_str(&camera_note);
    let faults: Vec<&'static str> = record.faults.iter().map(|f| f.code.name()).collect();
    if !faults.is_empty() {
        row.status = "faulted".into();
        row.faults.push_str(&faults.join(";"));
    } else if !record.completed {
        row.status = "faulted".into();
        row.faults = "the board did not report Done".into();
    }
    let rec = PointRecord {
        point,
        preparation: &prep,
        phi_used_by_the_plant: phi,
        plant_jump_height_m: f64::NAN,
        measured_jump_height_m: None,
        predicted_jump_height_m: row.predicted_jump_height_m,
        camera_frames: expected_frames,
        frames_lost: u32::try_from(log.meta.dropped_samples).unwrap_or(u32::MAX),
        faults,
        track_frames_flagged: flagged,
    };
    finish_folder(&rec, &params, &staging, &target)?;
    journal.append(Event::Analysed { point: point.index })?;
    Ok(row)
}

/// Track the rod in `frames` against the log's camera clock: (jump height, frames flagged,
/// what went wrong as a note for `faults`).
fn track(frames: &Path, ts: &TrackSpec, log: &AcqLog) -> (Option<f64>, Option<usize>, String) {
    let seq = match ImageSequence::open(frames.to_str().unwrap_or_default()) {
        Ok(s) => s,
        Err(e) => return (None, None, format!("frames: {e};")),
    };
    match track_sequence(&seq, ts, &log_clock(log)) {
        Ok(r) => (
            Some(r.apex.jump_height_m),
            Some(r.frames_flagged()),
            String::new(),
        ),
        Err(e) => (None, None, format!("tracking failed: {e};")),
    }
}

/// Move the frames the lab's camera software wrote into `capture` into `frames`, waiting up
/// to `timeout_s` for `expected` image files; returns how many images were moved.
fn collect_frames(
    capture: &Path,
    frames: &Path,
    expected: usize,
    timeout_s: f64,
) -> Result<usize, String> {
    let is_image = |p: &Path| {
        p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
            matches!(
                e.to_ascii_lowercase().as_str(),
                "png" | "tif" | "tiff" | "bmp"
            )
        })
    };
    let list = || -> Result<Vec<std::path::PathBuf>, String> {
        let rd = std::fs::read_dir(capture)
            .map_err(|e| format!("camera.capture_dir {}: {e}", capture.display()))?;
        Ok(rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
    };
    let until = std::time::Instant::now() + std::time::Duration::from_secs_f64(timeout_s);
    while list()?.iter().filter(|p| is_image(p)).count() < expected
        && std::time::Instant::now() < until
    {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::fs::create_dir_all(frames)
        .map_err(|e| format!("cannot create {}: {e}", frames.display()))?;
    let mut moved = 0;
    for p in list()? {
        let Some(name) = p.file_name() else { continue };
        let to = frames.join(name);
        if std::fs::rename(&p, &to).is_err() {
            if !p.exists() {
                // Gone between the listing and the move (a camera that renames its files into
                // place); not ours to move, and an image missing is counted by `moved`.
                continue;
            }
            std::fs::copy(&p, &to)
                .and_then(|_| std::fs::remove_file(&p))
                .map_err(|e| format!("cannot move {} into the point's folder: {e}", p.display()))?;
        }
        moved += usize::from(is_image(&to));
    }
    Ok(moved)
}

/// What a point's jump runs with.
struct JumpSetup {
    /// The achieved phi, within the presets.
    phi: f64,
    /// The sand at that phi.
    params: Params,
    /// The replay's (and the simulated rig's) model.
    model: ModelName,
    /// The jump.
    spec: HilSpec,
}

/// The jump of `point` on sand at the achieved phi (the presets interpolated there, not the
/// target).
fn jump_setup(f: &CampaignFile, point: &Point, prep: &Preparation) -> Result<JumpSetup, String> {
    let phi = prep.achieved_phi.clamp(PRESET_PHI_MIN, PRESET_PHI_MAX);
    let params = Params::preset(phi).map_err(|e| e.to_string())?;
    let model: ModelName = f.model.parse().map_err(|e| format!("{e}"))?;
    let kind = parse_kind(&point.kind).ok_or_else(|| format!("kind `{}`", point.kind))?;
    let mut spec = HilSpec::new(kind, point.freq_hz, point.tau_s, model);
    spec.gain_lowering = f.grid.gain_lowering.map(HilSpec::gain_lowering_factor);
    spec.camera_fps = f.camera.fps;
    Ok(JumpSetup {
        phi,
        params,
        model,
        spec,
    })
}

/// Journal `point`'s preparation; its row before the jump (a failed preparation's final
/// row).
fn record_preparation(
    journal: &mut Journal,
    point: &Point,
    prep: &Preparation,
) -> Result<ResultRow, String> {
    journal.append(Event::BedPrepared {
        point: point.index,
        preparation: prep.clone(),
    })?;
    Ok(new_row(point, prep))
}

/// A point's row before its jump (a failed preparation's final row).
fn new_row(point: &Point, prep: &Preparation) -> ResultRow {
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
    }
    row
}

/// The point's folder and its staging folder, both cleared (a point run again starts clean).
fn fresh_folders(
    dir: &Path,
    point: &Point,
) -> Result<(std::path::PathBuf, std::path::PathBuf), String> {
    let target = dir.join(point.folder());
    let staging = dir.join(format!("{}.partial", point.folder()));
    for d in [&target, &staging] {
        if d.exists() {
            std::fs::remove_dir_all(d).map_err(|e| format!("cannot clear {}: {e}", d.display()))?;
        }
    }
    std::fs::create_dir_all(&staging)
        .map_err(|e| format!("cannot create {}: {e}", staging.display()))?;
    Ok((target, staging))
}

/// Write `point.json` and `params.toml`, then give the folder its name.
fn finish_folder(
    rec: &PointRecord<'_>,
    params: &Params,
    staging: &Path,
    target: &Path,
) -> Result<(), String> {
    let json = serde_json::to_string_pretty(rec).map_err(|e| e.to_string())?;
    std::fs::write(staging.join("point.json"), json + "\n")
        .map_err(|e| format!("cannot write point.json: {e}"))?;
    std::fs::write(staging.join("params.toml"), params.to_toml())
        .map_err(|e| format!("cannot write params.toml: {e}"))?;
    std::fs::rename(staging, target).map_err(|e| format!("cannot finish {}: {e}", target.display()))
}
