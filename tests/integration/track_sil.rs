//! The rod camera end to end (docs/model.md section 6): a SIL delayed stutter's frames, rendered
//! by the simulated camera the firmware triggered, tracked, give the simulator's jump height
//! within 0.1 mm; `sandjumper track --log` writes the log again with the measured rod heights,
//! which `replay` then compares with its prediction; the camera's scale comes back from a
//! simulated slow move; bad input is exit status 2 with the reason.

use crate::hil_common;

use clap::Parser;
use hil_common::{params, sil};
use sandjumper_acqlog::{AcqLog, Column, LogMetadata, LogRow, ReadOptions};
use sandjumper_cli::cli::{Cli, EXIT_BAD_INPUT, execute};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_imaging::render::{CameraModel, write_png};
use sandjumper_imaging::sequence::ImageSequence;
use sandjumper_imaging::track::log_clock;
use sandjumper_imaging::track::{TrackSpec, track_sequence};
use sandjumper_model::ModelName;
use sandjumper_rig::hil::HilSpec;
use sandjumper_rig::hil::camera::{heights_by_period, write_frames};
use sandjumper_rig::hil::log::acquisition_log;

fn run(args: &[&str]) -> Result<(), (u8, String)> {
    let cli = Cli::try_parse_from(args).map_err(|e| (e.exit_code() as u8, e.to_string()))?;
    execute(cli).map_err(|e| (e.exit, e.message))
}

/// A SIL delayed stutter (eq4, phi 0.57, 10 Hz, tau 0.1 s, gain lowering 0.05) with its
/// frames and log in `dir`; returns the simulator's jump height and the true rod heights of
/// the camera frames.
fn delayed_stutter_with_frames(dir: &std::path::Path) -> (f64, Vec<(u32, f64)>) {
    let mut spec = HilSpec::new(JumpKind::DelayedStutter, 10.0, 0.1, ModelName::Eq4);
    spec.gain_lowering = Some(HilSpec::gain_lowering_factor(0.05));
    let p = params(0.57);
    let o = sil(&p, &spec);
    assert!(o.faults.is_empty());
    let camera = CameraModel::default();
    let n = write_frames(
        &o.camera_frames,
        &heights_by_period(&o),
        &camera,
        1e-4,
        &dir.join("frames"),
    )
    .unwrap();
    assert_eq!(n, o.camera_frames.len());
    acquisition_log(&o, &spec, 10_000, 1e-6, p.robot.stroke_amplitude_m, 0.57)
        .write_file(&dir.join("acquisition.csv"))
        .unwrap();
    // What each frame shows: the rod's mean height over its 1 ms exposure (10 periods).
    let heights = heights_by_period(&o);
    let truth = o
        .camera_frames
        .iter()
        .map(|f| {
            let k = f.period as usize;
            let span = &heights[k..(k + 11).min(heights.len())];
            let trapezoid = (span.iter().sum::<f64>() - 0.5 * (span[0] + span[span.len() - 1]))
                / (span.len() - 1) as f64;
            (f.frame, trapezoid)
        })
        .collect();
    (o.summary.jump_height_m, truth)
}

#[test]
fn tracked_frames_of_a_sil_delayed_stutter_give_the_simulated_jump_height() {
    let dir = tempfile::tempdir().unwrap();
    let (simulated, truth) = delayed_stutter_with_frames(dir.path());
    let seq = ImageSequence::open(dir.path().join("frames").to_str().unwrap()).unwrap();
    let log =
        AcqLog::read_file(&dir.path().join("acquisition.csv"), &ReadOptions::default()).unwrap();
    let camera = CameraModel::default();
    let spec = TrackSpec {
        exposure_s: camera.exposure_s,
        ..TrackSpec::new(camera.m_per_px)
    };
    let r = track_sequence(&seq, &spec, &log_clock(&log)).unwrap();
    assert_eq!(r.frames_flagged(), 0, "{:?}", r.flagged);
    assert!(r.rest_frames_used >= 30, "{}", r.rest_frames_used);
    assert_eq!(r.apex.method, "parabola");
    assert!(
        (r.apex.fitted_accel_m_s2.unwrap() + 9.81).abs() < 0.5,
        "{:?}",
        r.apex
    );
    // Against the simulator's jump height (relative to the plant's initial rest): 0.1 mm.
    let measured = r.apex.jump_height_m;
    assert!(
        (measured - simulated).abs() < 1e-4,
        "tracked {measured} m vs simulated {simulated} m"
    );
    // Against the truth measured the camera's way (the highest rod height minus the median
    // true height of the same rest frames): the camera's own error, a few micrometres.
    let mut rest: Vec<f64> = truth[..r.rest_frames_used].iter().map(|t| t.1).collect();
    rest.sort_by(f64::total_cmp);
    let rest_true = 0.5 * (rest[(rest.len() - 1) / 2] + rest[rest.len() / 2]);
    assert!(
        (measured - (simulated - rest_true)).abs() < 20e-6,
        "tracked {measured} m vs {} m",
        simulated - rest_true
    );
    // Every frame's height against the rod's true mean height over its exposure: RMS under
    // 0.05 px (6 um), the worst (a frame smeared over ~10 px) under 0.25 px.
    let (mut worst, mut sq): (f64, f64) = (0.0, 0.0);
    for (f, (n, h)) in r.frames.iter().zip(&truth) {
        assert_eq!(f.frame, u64::from(*n));
        let e = f.rod_height_m - (h - rest_true);
        worst = worst.max(e.abs());
        sq += e * e;
    }
    let rms = (sq / r.frames.len() as f64).sqrt();
    assert!(rms < 0.05 * camera.m_per_px, "RMS frame error {rms} m");
    assert!(
        worst < 0.25 * camera.m_per_px,
        "worst frame error {worst} m"
    );
}

#[test]
fn track_out_writes_its_files_and_the_log_that_replay_compares() {
    let dir = tempfile::tempdir().unwrap();
    let (_, _) = delayed_stutter_with_frames(dir.path());
    let out = dir.path().join("track");
    let p = |q: &std::path::Path| q.to_str().unwrap().to_string();
    run(&[
        "sandjumper",
        "track",
        &p(&dir.path().join("frames")),
        "--m-per-px",
        "1.2e-4",
        "--log",
        &p(&dir.path().join("acquisition.csv")),
        "--exposure",
        "0.001",
        "--out",
        &p(&out),
        "--json",
    ])
    .unwrap();
    for f in [
        "track.csv",
        "summary.json",
        "track.toml",
        "track.png",
        "track.svg",
        "acquisition.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "jump_height_m",
        "apex_time_s",
        "rest_height_px",
        "frames",
        "frames_flagged",
        "m_per_px",
    ] {
        assert!(summary.get(key).is_some(), "{key} missing");
    }
    let csv = std::fs::read_to_string(out.join("track.csv")).unwrap();
    assert!(csv.starts_with("frame,t_s,x_px,y_px,rod_height_m,status"));
    let log = AcqLog::read_file(&out.join("acquisition.csv"), &ReadOptions::default()).unwrap();
    let jump = summary["jump_height_m"].as_f64().unwrap();
    assert_eq!(log.meta.measured_jump_height_m, Some(jump));
    let cam_rows = log.rows.iter().filter(|r| r.camera_frame.is_some()).count();
    let measured_rows = log.rows.iter().filter(|r| r.rod_height_m.is_some()).count();
    assert_eq!(cam_rows, measured_rows);
    // Replay of the rewritten log: predicted vs measured.
    let replay_out = dir.path().join("replay");
    run(&[
        "sandjumper",
        "replay",
        &p(&out.join("acquisition.csv")),
        "--out",
        &p(&replay_out),
        "--json",
    ])
    .unwrap();
    let replay: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(replay_out.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(
        replay["measured"]["measured_jump_height_m"].as_f64(),
        Some(jump),
        "{replay}"
    );
}

#[test]
fn the_scale_comes_back_from_a_simulated_slow_move_against_the_encoder() {
    // The carriage clamped, the motor ramps p by 6 mm over 1.5 s (4 mm/s) while the camera
    // takes 200 frames/s: the rod, and its ball, move down by exactly dp.
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let camera = CameraModel {
        m_per_px: 1.05e-4,
        ..CameraModel::default()
    };
    let mut meta = LogMetadata::new(1000.0, 1e6);
    meta.source = Some("slow move".into());
    let mut log = AcqLog::new(meta, &[Column::CameraFrame]);
    let mut frame = 0;
    for k in 0..1500u64 {
        let t = k as f64 * 1e-3;
        let p = -0.003 + 0.004 * t;
        let mut row = LogRow::new(k, t, (p * 1e6).round() as i64);
        if k % 5 == 0 {
            row.camera_frame = Some(frame);
            let centre = camera.centre_px(-(p + 0.003));
            write_png(
                &camera.render_still(centre, frame),
                &frames.join(format!("frame_{frame:06}.png")),
            )
            .unwrap();
            frame += 1;
        }
        log.rows.push(row);
    }
    let log_path = dir.path().join("move.csv");
    log.write_file(&log_path).unwrap();
    let seq = ImageSequence::open(frames.to_str().unwrap()).unwrap();
    let scaled = sandjumper_imaging::camera_scale::scale_from(&seq, &log, 79.0, None).unwrap();
    let (fit, n, flagged) = (scaled.fit, scaled.frames, scaled.frames_flagged);
    assert_eq!((n, flagged), (300, 0));
    assert!(fit.direction_ok);
    assert!(fit.r_squared > 0.999_999, "{fit:?}");
    assert!((fit.m_per_px / 1.05e-4 - 1.0).abs() < 1e-3, "{fit:?}");
    // The command line.
    run(&[
        "sandjumper",
        "camera-scale",
        frames.to_str().unwrap(),
        "--log",
        log_path.to_str().unwrap(),
        "--ball-px",
        "80",
        "--json",
    ])
    .unwrap();
}

#[test]
fn bad_track_input_is_exit_status_2_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    let camera = CameraModel::default();
    for n in 0..4u32 {
        write_png(
            &camera.render_still((128.0, 700.0), u64::from(n)),
            &frames.join(format!("frame_{n:06}.png")),
        )
        .unwrap();
    }
    let f = frames.to_str().unwrap();
    let bad = |args: &[&str], needle: &str| {
        let mut all = vec!["sandjumper", "track", f];
        all.extend_from_slice(args);
        let (code, msg) = run(&all).unwrap_err();
        assert_eq!(code, EXIT_BAD_INPUT, "{args:?}: {msg}");
        assert!(msg.contains(needle), "{args:?}: {msg}");
    };
    bad(&["--m-per-px", "0", "--fps", "200"], "metres per pixel");
    bad(&["--m-per-px=-1e-4", "--fps", "200"], "metres per pixel");
    bad(&["--m-per-px", "nan", "--fps", "200"], "metres per pixel");
    bad(&["--m-per-px", "1.2e-4"], "--fps");
    bad(&["--m-per-px", "1.2e-4", "--fps", "0"], "frame rate");
    bad(
        &[
            "--m-per-px",
            "1.2e-4",
            "--fps",
            "200",
            "--roi",
            "200,0,100,100",
        ],
        "outside the 256x1024 frames",
    );
    bad(
        &["--m-per-px", "1.2e-4", "--fps", "200", "--roi", "1,2,3"],
        "X,Y,W,H",
    );
    // A log without camera frames; a log with more and with fewer camera ticks.
    let log_with = |frames_in_log: u64, name: &str| {
        let mut log = AcqLog::new(LogMetadata::new(1000.0, 1e6), &[Column::CameraFrame]);
        for k in 0..100u64 {
            let mut row = LogRow::new(k, k as f64 * 1e-3, 0);
            if k % 5 == 0 && k / 5 < frames_in_log {
                row.camera_frame = Some(k / 5);
            }
            log.rows.push(row);
        }
        let path = dir.path().join(name);
        log.write_file(&path).unwrap();
        path.to_str().unwrap().to_string()
    };
    let none = log_with(0, "none.csv");
    bad(
        &["--m-per-px", "1.2e-4", "--log", &none],
        "no camera frames",
    );
    let more = log_with(6, "more.csv");
    bad(
        &["--m-per-px", "1.2e-4", "--log", &more],
        "2 camera tick(s) without an image: frame 4, 5",
    );
    let fewer = log_with(3, "fewer.csv");
    bad(
        &["--m-per-px", "1.2e-4", "--log", &fewer],
        "1 frame number(s) not in the log: 3",
    );
    // An empty sequence.
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let (code, msg) = run(&[
        "sandjumper",
        "track",
        empty.to_str().unwrap(),
        "--m-per-px",
        "1e-4",
        "--fps",
        "200",
    ])
    .unwrap_err();
    assert_eq!(code, EXIT_BAD_INPUT);
    assert!(msg.contains("no frames"), "{msg}");
}
