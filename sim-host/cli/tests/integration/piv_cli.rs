//! `sandjumper piv-synthetic` and `sandjumper piv` from the command line, the contract: the
//! files `piv --out` writes (fields, arrays, flow table, figures, the added-mass table that
//! `fit added-mass` reads), `--json`, and bad input refused with exit status 2. What the
//! analysis finds (the cone's numbers, the files' contents, a log's timing) is tested on the
//! library: `sim-host/flow/tests/integration/piv_end_to_end.rs`.

use crate::common;
use common::{ok, refused};

/// The files `piv --out` writes for a calibrated run with a foot (the SI arrays and maps, the
/// added-mass table and figure among them) and `--json`'s object, on the smallest cone that
/// writes them all: 96 x 64 px, two passes. (The numbers of the full 320 x 256 cone and the
/// files' contents: `sim-host/flow/tests/integration/piv_end_to_end.rs`.)
#[test]
fn a_synthetic_cone_goes_through_piv_to_an_added_mass_table() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("cone");
    let f = frames.to_str().unwrap();
    ok(&[
        "piv-synthetic",
        "--field",
        "cone",
        "--size",
        "96x64",
        "--frames",
        "4",
        "--magnitude",
        "2",
        "--out",
        f,
    ]);
    let out = dir.path().join("piv");
    let foot = frames.join("foot.csv");
    let json = ok(&[
        "piv",
        f,
        "--foot",
        foot.to_str().unwrap(),
        "--m-per-px",
        "2e-4",
        "--fps",
        "500",
        "--origin",
        "48,16",
        "--windows",
        "32,16",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["pairs"], 3);
    assert!(v["vectors_masked"].as_u64().unwrap() > 0);
    for name in [
        "fields/0000.csv",
        "fields/0002.csv",
        "u_px.npy",
        "v_px.npy",
        "flag.npy",
        "s2n.npy",
        "u_m_s.npy",
        "shear_rate_1_s.npy",
        "flow.csv",
        "added_mass.csv",
        "piv.toml",
        "summary.json",
        "speed.png",
        "speed.svg",
        "shear_rate.png",
        "added_mass.png",
        "animation.gif",
    ] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
}

#[test]
fn bad_piv_input_is_refused_with_exit_status_2() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("f");
    let f = frames.to_str().unwrap();
    ok(&[
        "piv-synthetic",
        "--field",
        "shift",
        "--size",
        "128x96",
        "--frames",
        "3",
        "--out",
        f,
    ]);
    refused(
        &["piv", f, "--windows", "256,32"],
        &["larger than the 128x96 image"],
    );
    refused(&["piv", f, "--windows", "24"], &["power of two"]);
    refused(
        &["piv", f, "--min-speed-ratio", "1.5"],
        &["speed ratio", "0 to 1"],
    );
    refused(&["piv", f, "--windows", "16,32"], &["do not grow"]);
    refused(&["piv", f, "--windows", "a,b"], &["window sizes"]);
    refused(&["piv", f, "--overlap", "0.95"], &["overlap"]);
    refused(&["piv", f, "--overlap=-0.1"], &["overlap"]);
    refused(
        &[
            "piv",
            f,
            "--m-per-px",
            "0",
            "--fps",
            "500",
            "--origin",
            "1,1",
        ],
        &["not allowed"],
    );
    refused(
        &["piv", f, "--m-per-px", "1e-4", "--fps", "500"],
        &["--origin"],
    );
    refused(
        &["piv", f, "--m-per-px", "1e-4", "--origin", "1,1"],
        &["--fps or --log"],
    );
    // A mask of the wrong size.
    let mask = dir.path().join("mask.png");
    image::GrayImage::new(64, 64).save(&mask).unwrap();
    refused(
        &["piv", f, "--mask", mask.to_str().unwrap()],
        &["the frames' size"],
    );
    // One frame only; frames of two sizes.
    let one = dir.path().join("one");
    std::fs::create_dir(&one).unwrap();
    std::fs::copy(
        frames.join("frame_000000.png"),
        one.join("frame_000000.png"),
    )
    .unwrap();
    refused(&["piv", one.to_str().unwrap()], &["at least two"]);
    image::GrayImage::new(64, 64)
        .save(one.join("frame_000001.png"))
        .unwrap();
    refused(&["piv", one.to_str().unwrap()], &["differs from"]);
    // A bad foot file.
    let foot = dir.path().join("foot.csv");
    std::fs::write(&foot, "frame,x_px,y_px\n0,1,1\n0,2,2\n").unwrap();
    refused(
        &["piv", f, "--foot", foot.to_str().unwrap()],
        &["at least 3"],
    );
}

/// A log that lacks one of the frames is refused. (How a log times the pairs:
/// `sim-host/flow/tests/integration/piv_end_to_end.rs`.)
#[test]
fn a_log_that_lacks_a_frame_is_refused() {
    use sandjumper_acqlog::{AcqLog, Column, LogMetadata, LogRow};
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("f");
    let f = frames.to_str().unwrap();
    ok(&[
        "piv-synthetic",
        "--field",
        "shift",
        "--size",
        "128x96",
        "--frames",
        "3",
        "--out",
        f,
    ]);
    // Camera ticks for frames 0 and 1 only.
    let mut short = AcqLog::new(LogMetadata::new(10_000.0, 1e6), &[Column::CameraFrame]);
    for k in 0..100u64 {
        let mut row = LogRow::new(k, 0.5 + k as f64 * 1e-4, 0);
        row.camera_frame = match k {
            0 => Some(0),
            20 => Some(1),
            _ => None,
        };
        short.rows.push(row);
    }
    let spath = dir.path().join("short.csv");
    short.write_file(&spath).unwrap();
    refused(
        &["piv", f, "--log", spath.to_str().unwrap()],
        &["not in the log: 2"],
    );
}
