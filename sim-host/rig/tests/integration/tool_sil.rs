//! What the rig tool's commands measure through the simulated rig (`--link sil`: the core's
//! controller in this process), called as the library's typed requests: the status, a jump's
//! log, the slow intrusion's force-vs-depth curve, a replay that follows the jump it replays,
//! the replay plan's refusals, the drive calibration and `flash` on a simulated controller.
//! (The command line's files, flags and exit statuses: `sim-host/cli/tests/integration/rig_tool.rs`.)
//!
//! Tolerances:
//! - intrusion: against the `eq1` sand the first intrusion's curve rises with depth to more
//!   than 20 N at 19 mm (what `fit intrusion` recovers from it within 3 % is checked in
//!   `sim-host/study/tests/integration/rig_fit.rs`);
//! - replay: the replayed run's measured motor position follows the original run's within
//!   1.5 mm at every tick and 0.5 mm RMS (each run tracks its command within ~1 mm; the
//!   table is the original encoder record resampled at 1 kHz).

use std::path::Path;

use sandjumper_acqlog::{AcqLog, CheckRequest, ReadOptions};
use sandjumper_core::RigState;
use sandjumper_core::reset::ResetCause;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::params::ModelName;
use sandjumper_output::{Blame, Blamed, Silent, StagedDir};
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::tool::calibrate::{CalibrateRequest, acknowledge_reset, calibrate};
use sandjumper_rig::tool::flash::{FlashRequest, Flashed, flash};
use sandjumper_rig::tool::intrude::{self, IntrudeRequest};
use sandjumper_rig::tool::jump::{self, JumpOutcome, JumpRequest};
use sandjumper_rig::tool::replay::{self, ReplayRequest, plan};
use sandjumper_rig::tool::status::status;
use sandjumper_rig::tool::target::Target;

use crate::common;
use common::{log_rows, pngs_in, replay_error, replay_of_log};

fn sil() -> Target {
    Target::on(LinkArg::Sil)
}

/// `rig jump --kind single --freq 10 --link sil` with `camera_fps` frames/s.
fn single_jump(camera_fps: u32) -> JumpOutcome {
    let request = JumpRequest {
        camera_fps,
        ..JumpRequest::new(sil(), JumpKind::Single, 10.0)
    };
    request.validate().expect("a valid jump");
    jump::run(&request, &Silent).expect("the jump runs")
}

/// The controller on sil is idle, without a fault, and has dropped no sample.
#[test]
fn status_through_sil_reports_an_idle_controller() {
    let report = status(&sil(), &Silent).unwrap();
    assert_eq!(report.link, "sil");
    assert_eq!(report.status.state, RigState::Idle);
    assert!(report.status.fault.is_none() && report.fault_code.is_none());
    assert_eq!(report.status.counters.samples_dropped, 0);
    let json: serde_json::Value = serde_json::from_str(&report.printed(true).unwrap()).unwrap();
    assert_eq!(json["status"]["state"], "Idle");
    assert!(json["status"]["fault"].is_null());
}

/// A 10 Hz single jump through sil completes without a fault or a lost sample, tracks its
/// command within 2 mm, triggers a camera frame every 5 ms (200 fps) for at least the 0.1 s
/// trajectory, moves the motor over the stroke, and its log is one `log check` accepts, with
/// one row per sample. Written with its camera at 20 fps (rendering 160 frames at 200 fps takes
/// seconds; the count of frames is the run's), its folder holds one rendered PNG per frame.
#[test]
fn jump_through_sil_writes_a_complete_log_that_log_check_accepts() {
    let outcome = single_jump(200);
    assert!(outcome.completed);
    assert!(outcome.faults.is_empty(), "{:?}", outcome.faults);
    assert_eq!(outcome.dropped_samples, 0);
    assert!(outcome.tracking_error_max_m < 0.002);
    // 200 fps for at least the 0.1 s trajectory.
    assert!(outcome.camera_frames >= 20, "{}", outcome.camera_frames);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("acquisition.csv");
    outcome.log.write_file(&path).unwrap();
    // What `log check` reads: the written log, every row there.
    let checked = sandjumper_acqlog::check::run(
        &CheckRequest {
            file: path,
            allow_gaps: false,
        },
        &Silent,
    )
    .expect("log check accepts the log");
    let rows = log_rows(&checked.log);
    assert_eq!(rows.len(), outcome.samples);
    // The motor went from the bottom of the stroke to the top and back.
    let top = rows.iter().map(|r| r.1).max().unwrap();
    let bottom = rows.iter().map(|r| r.1).min().unwrap();
    assert!(
        top > 15_000 && bottom < -18_000,
        "stroke {bottom}..{top} counts"
    );
    // Each frame rendered by the simulated camera.
    let slow = single_jump(20);
    assert!(slow.camera_frames > 0);
    let out = slow
        .write(StagedDir::create(&dir.path().join("jump")).unwrap(), false)
        .unwrap();
    assert_eq!(pngs_in(&out.join("frames")), slow.camera_frames);
}

/// The slow intrusion into the `eq1` sand (the command's defaults: 20 mm at 10 mm/s, 0.5 s
/// holds, re-intrusion to 30 mm) measures a quasi-static force-vs-depth curve: depth strictly
/// increasing, force rising with depth, more than 20 N past 19 mm.
#[test]
fn intrusion_measures_the_sands_penetration_force() {
    let request = IntrudeRequest {
        model: ModelName::Eq1,
        ..IntrudeRequest::default()
    };
    request.validate().unwrap();
    let outcome = intrude::run(&request, &Silent).expect("the intrusion runs");
    assert!(outcome.completed, "{:?}", outcome.faults);
    let first = &outcome.intrusion;
    assert_eq!(first.len(), outcome.intrusion_points);
    assert!(first.len() >= 60, "{} points", first.len());
    for w in first.windows(2) {
        assert!(w[1].depth_m > w[0].depth_m, "depth strictly increases");
        // Quasi-static: the force rises with depth (a little noise from the loop allowed).
        assert!(
            w[1].force_n > w[0].force_n - 0.2,
            "force falls at {} m",
            w[1].depth_m
        );
    }
    let end = first.last().unwrap();
    assert!(
        end.depth_m > 0.019 && end.force_n > 20.0,
        "{} N at {} m",
        end.force_n,
        end.depth_m
    );
    assert_eq!(outcome.force_at_depth_n, Some(end.force_n));
    assert!(!outcome.reintrusion.is_empty());
}

/// The intrusion's MCAP log, written beside the CSV, holds one `/encoder` message per row of
/// the CSV and ends cleanly. A short program (40 mm/s, 50 ms holds: about 1.5 s of log, where
/// the defaults' 8.5 s take seconds to write as MCAP).
#[test]
fn the_intrusions_mcap_log_holds_every_row() {
    let short = IntrudeRequest {
        model: ModelName::Eq1,
        speed_m_s: 0.04,
        hold_s: 0.05,
        ..IntrudeRequest::default()
    };
    let outcome = intrude::run(&short, &Silent).unwrap();
    assert!(outcome.completed && outcome.faults.is_empty());
    let dir = tempfile::tempdir().unwrap();
    let out = outcome
        .write(
            StagedDir::create(&dir.path().join("intrude")).unwrap(),
            true,
        )
        .unwrap();
    let log = AcqLog::read_file(&out.join("acquisition.csv"), &ReadOptions::default()).unwrap();
    assert_eq!(log.rows.len(), outcome.samples);
    let mcap =
        sandjumper_acqlog::read_messages(&std::fs::read(out.join("acquisition.mcap")).unwrap());
    assert!(mcap.complete, "{:?}", mcap.stopped);
    let encoder = mcap
        .messages
        .iter()
        .filter(|m| m.topic == "/encoder")
        .count();
    assert_eq!(encoder, log.rows.len());
}

/// A jump's log replayed through sil: the checksum the controller verified is the one in the
/// new log's metadata, the run completes cleanly, and the measured motor follows the original
/// jump's within 1.5 mm (0.5 mm RMS) from the replay's start.
#[test]
fn a_replayed_jump_reproduces_the_original_motor_trajectory() {
    let original = single_jump(0);
    let outcome =
        replay::run(&replay_of_log(sil(), &original.log, "jump.csv"), &Silent).expect("replays");
    assert!(outcome.completed);
    assert!(outcome.faults.is_empty(), "{:?}", outcome.fault_names());
    let text = String::from_utf8(outcome.log.write_csv(Vec::new()).unwrap()).unwrap();
    assert!(
        text.contains(&format!("# replay_checksum: {}", outcome.checksum)),
        "{}",
        outcome.checksum
    );
    // The replay's trajectory starts with the original log's first sample.
    let (max, rms) = replay_error(&original.log, &outcome.log);
    assert!(max < 1.5e-3 && rms < 0.5e-3, "max {max} m, rms {rms} m");
}

/// Scaled beyond the stroke, stretched too fast for the drive's force or too slow for the
/// buffer: the jump's replay is refused before anything moves (the caller's input), saying
/// which limit.
#[test]
fn replays_beyond_the_stroke_the_force_or_the_buffer_are_refused_before_anything_moves() {
    let original = single_jump(0);
    let base = replay_of_log(sil(), &original.log, "jump.csv");
    for (scale, stretch, reason) in [
        (1.5, 1.0, "outside the stroke"),
        (1.0, 0.4, "of motor force"),
        (1.0, 6.0, "replay buffer holds 4096"),
    ] {
        let request = ReplayRequest {
            scale,
            time_stretch: stretch,
            ..base.clone()
        };
        let e = request.plan().expect_err("refused");
        assert_eq!(e.blame(), Blame::Input);
        let msg = e.to_string();
        assert!(
            msg.starts_with("jump.csv: refused before anything moved") && msg.contains(reason),
            "scale {scale}, stretch {stretch}: {msg}"
        );
        // `run` plans first: it refuses the same way without opening the link.
        assert!(replay::run(&request, &Silent).is_err());
    }
}

/// A one-cycle cosine `p = -A cos(2 pi f t)` sampled at 10 kHz for one period.
fn cosine_record(amplitude_m: f64, freq_hz: f64) -> Vec<(f64, f64)> {
    (0..=(10_000.0 / freq_hz) as usize)
        .map(|k| {
            let t = k as f64 / 10_000.0;
            (
                t,
                -amplitude_m * (std::f64::consts::TAU * freq_hz * t).cos(),
            )
        })
        .collect()
}

/// The replay plan's checks at their boundaries: 3 % below the frequency where the peak force
/// `m_m (A w^2 + g)` reaches the drive's 300 N passes (the table hitting the record at its own
/// sample times), 3 % above is refused; 25 mm of stroke passes, 25.1 mm does not; 4096 samples
/// fit the buffer, 4097 do not; a table rate that does not divide the control rate is refused.
#[test]
fn the_replay_plan_refuses_exactly_beyond_the_drives_force_and_the_stroke() {
    let (m_m, g, peak): (f64, f64, f64) = (1.125, 9.81, 300.0);
    // Peak force m_m (A w^2 + g): the frequency where it equals 300 N at A = 18.75 mm.
    let a: f64 = 0.01875;
    let f_limit = ((peak / m_m - g) / a).sqrt() / std::f64::consts::TAU;
    let below = plan(
        &cosine_record(a, 0.97 * f_limit),
        1000,
        10_000,
        m_m,
        g,
        peak,
    )
    .unwrap();
    assert!(below.peak_force_n < peak && below.peak_force_n > 0.9 * peak);
    assert_eq!(below.period_ticks, 10);
    // The table hits the record at its own sample times (every 10th 10 kHz sample).
    let rec = cosine_record(a, 0.97 * f_limit);
    for (k, p) in below.samples.iter().enumerate() {
        assert!((f64::from(*p) - rec[10 * k].1).abs() < 1e-9);
    }
    let above = plan(
        &cosine_record(a, 1.03 * f_limit),
        1000,
        10_000,
        m_m,
        g,
        peak,
    );
    let msg = above.unwrap_err().to_string();
    assert!(msg.contains("of motor force"), "{msg}");
    // Stroke: 25 mm is allowed, 25.1 mm is not.
    assert!(plan(&cosine_record(0.025, 5.0), 1000, 10_000, m_m, g, peak).is_ok());
    let msg = plan(&cosine_record(0.0251, 5.0), 1000, 10_000, m_m, g, peak)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("outside the stroke"), "{msg}");
    // Buffer: 4096 samples fit, 4097 do not.
    let long = |n: usize| -> Vec<(f64, f64)> { (0..n).map(|k| (k as f64 / 1000.0, 0.0)).collect() };
    assert_eq!(
        plan(&long(4096), 1000, 10_000, m_m, g, peak)
            .unwrap()
            .samples
            .len(),
        4096
    );
    let msg = plan(&long(4097), 1000, 10_000, m_m, g, peak)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("buffer holds 4096"), "{msg}");
    // A table rate that does not divide the control rate.
    assert!(plan(&long(10), 3000, 10_000, m_m, g, peak).is_err());
}

/// The drive calibration is sent (the controller reports it: 0 N -> code 2100), saved in its
/// file, and sent again from the file by a later program (the status shows it, after a
/// power-on reset); codes the core refuses and a file with an unknown key are the caller's
/// input, naming the flag or the file and the key; a reset is acknowledged.
#[test]
fn the_drive_calibration_is_sent_saved_and_sent_again_from_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("drive.toml");
    let request = CalibrateRequest {
        target: sil(),
        zero_code: 2100,
        codes_per_newton: 6.5,
        save: Some(file.clone()),
    };
    let sent = calibrate(&request, &Silent).unwrap();
    assert_eq!(sent.calibration.zero_code, 2100);
    assert_eq!(sent.calibration.codes_per_newton, 6.5);
    assert_eq!(sent.calibration.force_to_code(0.0), 2100);
    assert!(sent.to_string().contains("0 N -> code 2100"), "{sent}");
    let with_file = Target {
        drive_calibration: Some(file.clone()),
        ..sil()
    };
    let report = status(&with_file, &Silent).unwrap();
    assert_eq!(report.status.drive_calibration.zero_code, 2100);
    assert_eq!(report.status.drive_calibration.codes_per_newton, 6.5);
    assert_eq!(report.status.reset_cause, ResetCause::PowerOn);
    let bad_codes = CalibrateRequest {
        zero_code: 3000,
        save: None,
        ..request
    };
    let e = calibrate(&bad_codes, &Silent).unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(e.to_string().contains("--zero-code"), "{e}");
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "zero_code = 2100\ngain = 6.5\n").unwrap();
    let e = status(
        &Target {
            drive_calibration: Some(bad.clone()),
            ..sil()
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    let msg = e.to_string();
    assert!(
        msg.contains(bad.to_str().unwrap()) && msg.contains("gain"),
        "{msg}"
    );
    let ack = acknowledge_reset(&sil(), &Silent).unwrap();
    assert_eq!(ack.reset_cause, ResetCause::PowerOn);
}

/// `flash` on sil has nothing to do and says so; for a board it refuses (the caller's input)
/// a probe-rs that is not there and a firmware file that is not there, naming them.
#[test]
fn flash_is_a_no_op_for_sil_and_says_what_is_missing_for_a_board() {
    let flashed = flash(
        &FlashRequest {
            target: sil(),
            ..FlashRequest::default()
        },
        &Silent,
    )
    .unwrap();
    assert!(matches!(flashed, Flashed::Nothing(_)));
    assert!(flashed.to_string().contains("nothing to flash"));
    let dir = tempfile::tempdir().unwrap();
    let elf = dir.path().join("fw.elf");
    std::fs::write(&elf, b"\x7fELF").unwrap();
    let board = |firmware: &Path| Target {
        firmware: Some(firmware.to_path_buf()),
        ..Target::on(LinkArg::Serial("/dev/ttyACM0".into()))
    };
    let e = flash(
        &FlashRequest {
            target: board(&elf),
            probe_rs: dir.path().join("no-probe-rs"),
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(e.to_string().contains("probe-rs not found"), "{e}");
    let e = flash(
        &FlashRequest {
            target: board(&dir.path().join("none.elf")),
            ..FlashRequest::default()
        },
        &Silent,
    )
    .unwrap_err();
    assert!(e.to_string().contains("none.elf"), "{e}");
}
