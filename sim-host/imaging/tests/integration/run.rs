//! `sandjumper track` and `camera-scale` as library calls: the typed outcome in memory, its
//! summary and folder, and the command line's messages for a refused request.

use std::path::Path;

use sandjumper_imaging::camera_scale::{self, ScaleRequest};
use sandjumper_imaging::render::{CameraModel, write_png};
use sandjumper_imaging::run::{self, TrackRequest};
use sandjumper_output::{Blame, Blamed, Silent};

const FPS: f64 = 500.0;
const APEX_T: f64 = 0.12;
const APEX_H: f64 = 0.03;

/// Rod height at `t`: 20 frames at rest, then a parabola up to `APEX_H` at `APEX_T`, m.
fn height(t: f64) -> f64 {
    let h = APEX_H - 0.5 * 9.81 * (t - APEX_T).powi(2);
    if t < 0.04 { 0.0 } else { h.max(0.0) }
}

/// `n` frames of the default camera watching `height`, written into `dir`.
fn frames(dir: &Path, n: u32) -> CameraModel {
    let cam = CameraModel::default();
    std::fs::create_dir_all(dir).unwrap();
    let bg = cam.background_image();
    for k in 0..n {
        let t0 = f64::from(k) / FPS;
        let f = cam.render_on(&bg, t0, |t| cam.centre_px(height(t)), u64::from(k));
        write_png(&f, &dir.join(format!("frame_{k:06}.png"))).unwrap();
    }
    cam
}

#[test]
fn a_rendered_jump_is_measured_in_memory_and_written_as_the_cli_writes_it() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("frames");
    let cam = frames(&dir, 100);
    let request = TrackRequest {
        frames: dir.display().to_string(),
        m_per_px: cam.m_per_px,
        fps: Some(FPS),
        ..TrackRequest::default()
    };
    let outcome = run::run(&request, &Silent).unwrap();
    assert_eq!(outcome.frames, 100);
    assert_eq!(outcome.result.frames.len(), 100);
    assert_eq!(outcome.time_source, "fps");
    assert!(
        (outcome.jump_height_m - APEX_H).abs() < 3e-4,
        "jump height {} m",
        outcome.jump_height_m
    );
    assert!(
        (outcome.apex_time_s - APEX_T).abs() < 3e-3,
        "{}",
        outcome.apex_time_s
    );
    let json = outcome.summary_json().unwrap();
    let keys: Vec<&str> = json
        .lines()
        .filter_map(|l| l.strip_prefix("  \"")?.split('"').next())
        .collect();
    assert_eq!(
        keys,
        [
            "jump_height_m",
            "apex_time_s",
            "apex",
            "rest_height_px",
            "rest_frames",
            "rest_rule",
            "frames",
            "frames_flagged",
            "flagged",
            "m_per_px",
            "time_source",
            "frame_size",
            "spec"
        ]
    );
    assert!(
        outcome
            .to_string()
            .starts_with("track: 100 frames (0 flagged), time from fps\n")
    );
    let out = outcome.write(&tmp.path().join("out")).unwrap();
    for name in [
        "track.csv",
        "summary.json",
        "track.toml",
        "track.png",
        "track.svg",
    ] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    assert!(
        !out.join("acquisition.csv").exists(),
        "no log, no acquisition.csv"
    );
}

#[test]
fn refused_requests_say_what_the_command_line_says() {
    let untimed = TrackRequest {
        frames: "frames".into(),
        m_per_px: 1e-4,
        ..TrackRequest::default()
    };
    let e = untimed.validate().unwrap_err();
    assert_eq!(e.to_string(), "give --fps or --log to time the frames");
    assert_eq!(e.blame(), Blame::Input);
    let missing = TrackRequest {
        frames: "/nonexistent/frames".into(),
        fps: Some(FPS),
        ..untimed
    };
    assert!(
        run::run(&missing, &Silent)
            .unwrap_err()
            .to_string()
            .starts_with("frames: ")
    );
    let tmp = tempfile::tempdir().unwrap();
    frames(&tmp.path().join("f"), 2);
    let no_log = ScaleRequest {
        frames: tmp.path().join("f").display().to_string(),
        log: tmp.path().join("missing.csv"),
        ball_px: 79.0,
        roi: None,
    };
    let e = camera_scale::run(&no_log, &Silent).unwrap_err();
    assert!(e.to_string().starts_with("--log "), "{e}");
    assert_eq!(e.blame(), Blame::Input);
}

#[test]
fn the_value_parsers_name_what_is_allowed() {
    use sandjumper_imaging::run::{parse_exposure, parse_fps, parse_m_per_px, parse_roi};
    assert_eq!(parse_fps("500"), Ok(500.0));
    assert_eq!(
        parse_fps("0"),
        Err("`0` is not a frame rate in frames/s: a finite number > 0".into())
    );
    assert_eq!(
        parse_m_per_px("-1"),
        Err("`-1` is not a scale in metres per pixel: a finite number > 0".into())
    );
    assert_eq!(parse_exposure("0"), Ok(0.0));
    assert_eq!(
        parse_exposure("-0.001"),
        Err("`-0.001` is not an exposure time: seconds >= 0".into())
    );
    let roi = parse_roi("1, 2,30,40").unwrap();
    assert_eq!((roi.x, roi.y, roi.width, roi.height), (1, 2, 30, 40));
    assert_eq!(
        parse_roi("1,2,0,40"),
        Err("`1,2,0,40` is not a region: X,Y,W,H in whole pixels, W and H > 0".into())
    );
}
