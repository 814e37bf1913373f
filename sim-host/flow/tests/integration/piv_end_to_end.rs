//! `piv_synthetic::run` and `run::run_into` end to end: a descending foot's cone analysed
//! into fields, arrays, the flow table and the added-mass table that `fit added-mass` reads
//! (the numbers from the outcome in memory, the files' contents from the folder), and an
//! acquisition log timing the pairs. (Which files `sandjumper piv --out` writes, its `--json`
//! and its refusals stay in `sim-host/cli/tests/integration/piv_cli.rs`.)

use std::path::Path;

use sandjumper_acqlog::{AcqLog, Column, LogMetadata, LogRow};
use sandjumper_flow::FlowError;
use sandjumper_flow::piv_synthetic::{self, SyntheticField, SyntheticRequest};
use sandjumper_flow::run::{self, PivRequest};
use sandjumper_output::Silent;

/// The sequence `request` asks for, written into `dir`; its path.
fn synthetic(dir: &Path, request: &SyntheticRequest) -> std::path::PathBuf {
    piv_synthetic::run(request, &Silent)
        .unwrap()
        .write(dir)
        .unwrap()
}

/// The cone of `piv-synthetic --field cone --size 320x256 --frames 4 --magnitude 2` through
/// `piv --foot foot.csv --m-per-px 2e-4 --fps 500 --origin 160,64 --out DIR`, the defaults
/// otherwise: three pairs, the foot masked, SI fields in every pair, a positive added mass at
/// every depth; and the folder's tables, arrays and settings say so.
#[test]
fn a_synthetic_cone_goes_through_piv_to_an_added_mass_table() {
    let dir = tempfile::tempdir().unwrap();
    let frames = synthetic(
        &dir.path().join("cone"),
        &SyntheticRequest {
            field: SyntheticField::Cone,
            size_px: (320, 256),
            frames: 4,
            magnitude_px: 2.0,
            ..SyntheticRequest::default()
        },
    );
    let f = frames.to_str().unwrap();
    let request = PivRequest {
        frames: f.into(),
        foot: Some(frames.join("foot.csv")),
        m_per_px: Some(2e-4),
        fps: Some(500.0),
        origin_px: Some((160.0, 64.0)),
        ..PivRequest::default()
    };
    let (outcome, out) = run::run_into(&request, &dir.path().join("piv"), &Silent).unwrap();
    assert_eq!(outcome.pairs, 3);
    assert!(outcome.vectors_masked > 0);
    // The SI fields of every pair (what u_m_s.npy and shear_rate_1_s.npy stack).
    assert!(outcome.run.results.iter().all(|r| r.si.is_some()));
    // The foot descends: the table `fit added-mass` reads has positive added masses.
    let added_mass = outcome.run.added_mass_points();
    assert_eq!(added_mass.len(), 3, "{added_mass:?}");
    for (z, m) in &added_mass {
        assert!(*m > 0.0, "{z},{m}");
    }

    // The files' contents.
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
    // added_mass.csv holds the added masses above, one row per depth.
    let table = std::fs::read_to_string(out.join("added_mass.csv")).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(rows[0], "depth_m,added_mass_kg");
    assert_eq!(rows.len(), 4, "{table}");
    for (r, (z, m)) in rows[1..].iter().zip(&added_mass) {
        assert_eq!(*r, format!("{z},{m}"));
    }
}

/// The shift of `piv-synthetic --field shift --size 128x96 --frames 3` (2.5, 1.25) px per
/// frame, timed by an acquisition log's camera ticks (the trigger, not a nominal rate): each
/// pair's time is the middle of its frames' and its velocity follows its own interval; a log
/// that lacks a frame is refused.
#[test]
fn the_acquisition_log_times_the_pairs() {
    let dir = tempfile::tempdir().unwrap();
    let frames = synthetic(
        &dir.path().join("f"),
        &SyntheticRequest {
            field: SyntheticField::Shift,
            size_px: (128, 96),
            frames: 3,
            ..SyntheticRequest::default()
        },
    );
    // Camera ticks at 0.5 s, 0.502 s and 0.5045 s.
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
    let request = PivRequest {
        frames: frames.display().to_string(),
        log: Some(path),
        m_per_px: Some(1e-4),
        origin_px: Some((64.0, 0.0)),
        ..PivRequest::default()
    };
    let outcome = run::run(&request, &Silent).unwrap();
    let t: Vec<f64> = outcome.flow.iter().map(|r| r.t_s).collect();
    assert!(
        (t[0] - 0.501).abs() < 1e-9 && (t[1] - 0.50325).abs() < 1e-9,
        "{t:?}"
    );
    // The velocity of the shift (2.5, 1.25) px per frame follows each pair's own interval:
    // u in m/s of the vector in the middle row of each pair's `fields/NNNN.csv`.
    let mid = |pair: usize| -> f64 {
        let u = &outcome.run.results[pair].si.as_ref().unwrap().u.values;
        u[u.len().div_ceil(2) - 1]
    };
    assert!((mid(0) - 2.5e-4 / 0.002).abs() < 0.03 * 0.125, "{}", mid(0));
    assert!((mid(1) - 2.5e-4 / 0.0025).abs() < 0.03 * 0.1, "{}", mid(1));
    // A log that lacks a frame.
    let mut short = log.clone();
    for r in &mut short.rows {
        if r.camera_frame == Some(2) {
            r.camera_frame = None;
        }
    }
    let spath = dir.path().join("short.csv");
    short.write_file(&spath).unwrap();
    let e = run::run(
        &PivRequest {
            log: Some(spath),
            ..request
        },
        &Silent,
    )
    .unwrap_err();
    assert!(
        matches!(e, FlowError::Input(_)) && e.to_string().contains("not in the log: 2"),
        "{e}"
    );
}
