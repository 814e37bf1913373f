//! `sandjumper piv-synthetic` and `sandjumper piv` from the command line: a descending
//! foot's cone analysed end to end (fields, arrays, flow table, figures, the added-mass table
//! that `fit added-mass` reads), and bad input refused with exit status 2.

mod common;
use common::{ok, refused};

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
        "320x256",
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
        "160,64",
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
    let fields = std::fs::read_to_string(out.join("fields/0000.csv")).unwrap();
    assert!(fields.starts_with(
        "x_px,y_px,u_px,v_px,flag,s2n,x_m,h_m,u_m_s,v_m_s,vorticity_1_s,shear_rate_1_s"
    ));
    // numpy's format: magic, version, a header naming the shape (pairs, rows, columns).
    let npy = std::fs::read(out.join("u_px.npy")).unwrap();
    assert_eq!(&npy[..6], b"\x93NUMPY");
    let header = String::from_utf8_lossy(&npy[10..120]);
    assert!(header.contains("'shape': (3, "), "{header}");
    // piv.toml reads back as the resolved settings of this run.
    let settings: toml::Value =
        toml::from_str(&std::fs::read_to_string(out.join("piv.toml")).unwrap()).unwrap();
    assert_eq!(settings["frames"].as_str(), Some(f));
    assert_eq!(settings["fps"].as_float(), Some(500.0));
    assert_eq!(settings["pairs"].as_str(), Some("consecutive"));
    assert_eq!(settings["calibration"]["m_per_px"].as_float(), Some(2e-4));
    let windows: Vec<i64> = settings["piv"]["windows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_integer().unwrap())
        .collect();
    assert_eq!(windows, [64, 32, 16]);
    assert_eq!(
        settings["preprocess"]["clahe_tile_px"].as_integer(),
        Some(0)
    );
    assert_eq!(
        settings["preprocess"]["local_contrast_sigma_px"].as_float(),
        Some(4.0)
    );
    // The paper's control volume, the column under the foot, beside the whole window's.
    let flow = std::fs::read_to_string(out.join("flow.csv")).unwrap();
    assert!(
        flow.lines()
            .next()
            .unwrap()
            .contains("momentum_kg_m_s,momentum_under_foot_kg_m_s,added_mass_kg"),
        "{flow}"
    );
    // The foot descends: the table `fit added-mass` reads has positive added masses.
    let table = std::fs::read_to_string(out.join("added_mass.csv")).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(rows[0], "depth_m,added_mass_kg");
    assert_eq!(rows.len(), 4, "{table}");
    for r in &rows[1..] {
        let m: f64 = r.split(',').nth(1).unwrap().parse().unwrap();
        assert!(m > 0.0, "{r}");
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

#[test]
fn the_acquisition_log_times_the_pairs() {
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
    // Camera ticks at 0.5 s, 0.502 s and 0.5045 s (the trigger, not a nominal rate).
    let mut log = AcqLog::new(LogMetadata::new(10_000.0, 1e6), &[Column::CameraFrame]);
    for k in 0..100u64 {
        let mut row = LogRow::new(k, 0.5 + k as f64 * 1e-4, 0);
        row.camera_frame = match k {
            0 => Some(0),
            20 => Some(1),
            45 => Some(2),
            _ => None,
        };
        log.rows.push(row);
    }
    let path = dir.path().join("acq.csv");
    log.write_file(&path).unwrap();
    let out = dir.path().join("piv");
    ok(&[
        "piv",
        f,
        "--log",
        path.to_str().unwrap(),
        "--m-per-px",
        "1e-4",
        "--origin",
        "64,0",
        "--out",
        out.to_str().unwrap(),
    ]);
    let flow = std::fs::read_to_string(out.join("flow.csv")).unwrap();
    let t: Vec<f64> = flow
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(3).unwrap().parse().unwrap())
        .collect();
    assert!(
        (t[0] - 0.501).abs() < 1e-9 && (t[1] - 0.50325).abs() < 1e-9,
        "{t:?}"
    );
    // The velocity of the shift (2.5, 1.25) px per frame follows each pair's own interval.
    let u0 = std::fs::read_to_string(out.join("fields/0000.csv")).unwrap();
    let u1 = std::fs::read_to_string(out.join("fields/0001.csv")).unwrap();
    let mid = |s: &str| -> f64 {
        let rows: Vec<&str> = s.lines().collect();
        rows[rows.len() / 2]
            .split(',')
            .nth(8)
            .unwrap()
            .parse()
            .unwrap()
    };
    assert!(
        (mid(&u0) - 2.5e-4 / 0.002).abs() < 0.03 * 0.125,
        "{}",
        mid(&u0)
    );
    assert!(
        (mid(&u1) - 2.5e-4 / 0.0025).abs() < 0.03 * 0.1,
        "{}",
        mid(&u1)
    );
    // A log that lacks a frame.
    let mut short = log.clone();
    for r in &mut short.rows {
        if r.camera_frame == Some(2) {
            r.camera_frame = None;
        }
    }
    let spath = dir.path().join("short.csv");
    short.write_file(&spath).unwrap();
    refused(
        &["piv", f, "--log", spath.to_str().unwrap()],
        &["not in the log: 2"],
    );
}
