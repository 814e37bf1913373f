//! `sandjumper hil` from the command line (in-process): `--out` writes the acquisition log in
//! the logs' format (it reads back, one row per tick, rod heights on camera rows), the
//! parameters, the summary and the figure; bad input is an error with exit status 2.

use clap::Parser;
use sandjumper_acqlog::{AcqLog, ReadOptions};
use sandjumper_cli::cli::{Cli, EXIT_BAD_INPUT, execute};

fn run(args: &[&str]) -> Result<(), (u8, String)> {
    let mut all = vec!["sandjumper", "hil"];
    all.extend_from_slice(args);
    let cli = Cli::try_parse_from(all).map_err(|e| (e.exit_code() as u8, e.to_string()))?;
    execute(cli).map_err(|e| (e.exit, e.message))
}

#[test]
fn out_writes_a_readable_acquisition_log_and_a_figure() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("hil");
    let out_s = out.to_str().expect("utf-8 path");
    run(&[
        "--link", "sil", "--kind", "single", "--freq", "10", "--model", "eq4", "--phi", "0.6",
        "--out", out_s, "--json",
    ])
    .expect("hil runs");
    for f in [
        "acquisition.csv",
        "params.toml",
        "summary.json",
        "hil.png",
        "hil.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let log = AcqLog::read_file(&out.join("acquisition.csv"), &ReadOptions::default())
        .expect("log reads");
    assert_eq!(log.meta.rate_hz, 10_000.0);
    assert_eq!(log.meta.counts_per_m, 1e6);
    assert_eq!(log.meta.dropped_samples, 0);
    assert!(log.rows.len() > 3000, "{} rows", log.rows.len());
    let frames: Vec<_> = log
        .rows
        .iter()
        .filter(|r| r.camera_frame.is_some())
        .collect();
    assert!(frames.len() > 10);
    assert!(
        frames.iter().all(|r| r.rod_height_m.is_some()),
        "every camera row has its rod height"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
            .expect("json");
    for key in [
        "jump_height_m",
        "ticks",
        "frames_lost",
        "faults",
        "camera_frames",
        "wall_time_s",
        "realtime_factor",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    assert_eq!(summary["camera_frames"].as_u64(), Some(frames.len() as u64));
    // The simulated camera rendered one PNG per camera row, numbered like the log, and wrote
    // its model.
    let pngs = std::fs::read_dir(out.join("frames"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "png")
        })
        .count();
    assert_eq!(pngs, frames.len());
    let last = frames.last().unwrap().camera_frame.unwrap();
    assert!(out.join(format!("frames/frame_{last:06}.png")).is_file());
    assert!(out.join("frames/camera.toml").is_file());
}

#[test]
fn a_camera_file_changes_the_frames_and_a_bad_one_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cam = dir.path().join("camera.toml");
    std::fs::write(&cam, "width_px = 128\nheight_px = 900\nbits = 16\n").unwrap();
    let out = dir.path().join("hil");
    run(&[
        "--kind",
        "single",
        "--freq",
        "10",
        "--camera",
        cam.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ])
    .expect("hil runs");
    let seq =
        sandjumper_imaging::sequence::ImageSequence::open(out.join("frames").to_str().unwrap())
            .unwrap();
    let first = seq.nth(0).unwrap().unwrap().frame;
    assert_eq!((first.width(), first.height()), (128, 900));
    assert_eq!(first.depth().bits(), 16);
    for (text, says) in [
        ("widht_px = 128\n", "unknown key `widht_px`"),
        ("m_per_px = -1.0\n", "m_per_px"),
        ("bits = 12\n", "bits"),
    ] {
        std::fs::write(&cam, text).unwrap();
        let (code, msg) = run(&[
            "--kind",
            "single",
            "--freq",
            "10",
            "--camera",
            cam.to_str().unwrap(),
        ])
        .unwrap_err();
        assert_eq!(code, EXIT_BAD_INPUT, "{text}: {msg}");
        assert!(msg.contains(says), "{text}: {msg}");
    }
}

#[test]
fn bad_input_is_refused_with_status_2() {
    for (args, says) in [
        (
            vec!["--link", "usb", "--kind", "single", "--freq", "10"],
            "unknown link",
        ),
        (
            vec!["--link", "serial:", "--kind", "single", "--freq", "10"],
            "unknown link",
        ),
        (
            vec!["--kind", "single", "--freq", "10", "--gain-lowering", "0"],
            "gain-lowering factor",
        ),
        (
            vec!["--kind", "single", "--freq", "10", "--gain-lowering", "1.5"],
            "gain-lowering factor",
        ),
        (vec!["--kind", "single", "--freq", "100"], "frequency"),
        (vec!["--kind", "delayed", "--freq", "10"], "--tau"),
        (
            vec!["--kind", "single", "--freq", "10", "--rtol", "1"],
            "rtol",
        ),
        (
            vec![
                "--link",
                "pil",
                "--firmware",
                "/nonexistent/elf",
                "--kind",
                "single",
                "--freq",
                "10",
            ],
            "not found",
        ),
        (
            vec![
                "--link",
                "serial:/nonexistent/tty",
                "--kind",
                "single",
                "--freq",
                "10",
            ],
            "serial port",
        ),
    ] {
        let (code, message) = run(&args).expect_err("must fail");
        assert_eq!(code, EXIT_BAD_INPUT, "{args:?}: {message}");
        assert!(
            message.contains(says),
            "{args:?}: `{message}` should mention `{says}`"
        );
    }
}
