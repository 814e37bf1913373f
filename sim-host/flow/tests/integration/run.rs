//! `sandjumper piv` and `piv-synthetic` as library calls: the typed outcome in memory, its
//! summary, its folder, and the command line's messages for a refused request.

use std::path::Path;

use sandjumper_flow::FlowError;
use sandjumper_flow::piv::PivConfig;
use sandjumper_flow::piv_synthetic::{self, SyntheticField, SyntheticRequest};
use sandjumper_flow::run::{self, PivRequest};
use sandjumper_output::{Blame, Blamed, Silent};

/// `frames` frames of `field` at `size` px written into `dir`.
fn synthetic(
    dir: &Path,
    field: SyntheticField,
    size: (u32, u32),
    frames: u32,
    shift: Option<(f64, f64)>,
) {
    let request = SyntheticRequest {
        field,
        size_px: size,
        frames,
        shift_px: shift,
        ..SyntheticRequest::default()
    };
    piv_synthetic::run(&request, &Silent)
        .unwrap()
        .write(dir)
        .unwrap();
}

fn two_passes(frames: &Path) -> PivRequest {
    PivRequest {
        frames: frames.display().to_string(),
        piv: PivConfig {
            windows: vec![32, 16],
            ..PivConfig::default()
        },
        ..PivRequest::default()
    }
}

fn mean_finite(v: &[f64]) -> f64 {
    let ok: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    ok.iter().sum::<f64>() / ok.len() as f64
}

#[test]
fn a_known_shift_is_recovered_in_memory_and_the_folder_holds_what_the_cli_writes() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    synthetic(
        &frames,
        SyntheticField::Shift,
        (128, 128),
        3,
        Some((1.6, -0.7)),
    );
    let outcome = run::run(&two_passes(&frames), &Silent).unwrap();
    assert_eq!(outcome.pairs, 2);
    assert_eq!(outcome.flow.len(), 2);
    assert_eq!(outcome.run.results.len(), 2);
    for r in &outcome.run.results {
        let (u, v) = (mean_finite(&r.field.u), mean_finite(&r.field.v));
        assert!(
            (u - 1.6).abs() < 0.05 && (v + 0.7).abs() < 0.05,
            "({u}, {v})"
        );
    }
    assert!(!outcome.calibrated);
    assert_eq!(outcome.grid.2, 8, "16 px windows at 0.5 overlap");
    let json = outcome.summary_json().unwrap();
    let keys: Vec<&str> = json
        .lines()
        .filter_map(|l| l.strip_prefix("  \"")?.split('"').next())
        .collect();
    assert_eq!(
        keys,
        [
            "pairs",
            "grid",
            "vectors",
            "vectors_replaced",
            "vectors_masked",
            "median_peak_ratio",
            "calibrated",
            "flow",
            "piv",
            "preprocess"
        ]
    );
    assert!(outcome.to_string().starts_with("piv: 2 pairs, grid "));
    let out = outcome.write(&tmp.path().join("out")).unwrap();
    for name in [
        "summary.json",
        "flow.csv",
        "added_mass.csv",
        "piv.toml",
        "u_px.npy",
        "fields/0001.csv",
        "speed.png",
        "animation.gif",
    ] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    assert!(
        !out.join("shear_rate.png").exists(),
        "uncalibrated: no shear rate map"
    );
}

#[test]
fn a_calibrated_cone_run_gives_the_added_mass_under_the_foot() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("cone");
    synthetic(&frames, SyntheticField::Cone, (256, 192), 4, None);
    let request = PivRequest {
        foot: Some(frames.join("foot.csv")),
        m_per_px: Some(2e-4),
        fps: Some(500.0),
        origin_px: Some((128.0, 48.0)),
        ..two_passes(&frames)
    };
    let outcome = run::run(&request, &Silent).unwrap();
    assert!(outcome.calibrated);
    assert!(outcome.vectors_masked > 0);
    assert!(outcome.run.results.iter().all(|r| r.si.is_some()));
    assert!(
        outcome
            .flow
            .iter()
            .any(|r| r.added_mass_kg.is_finite() && r.added_mass_kg > 0.0),
        "{:?}",
        outcome.flow
    );
    assert!(outcome.to_string().contains("last pair with the foot"));
}

#[test]
fn refused_requests_say_what_the_command_line_says() {
    let no_origin = PivRequest {
        m_per_px: Some(1e-4),
        fps: Some(500.0),
        ..PivRequest::default()
    };
    let e = no_origin.validate().unwrap_err();
    assert_eq!(
        e.to_string(),
        "--m-per-px needs --origin X,Y (the foot's axis at the surface, px)"
    );
    assert_eq!(e.blame(), Blame::Input);
    let untimed = PivRequest {
        m_per_px: Some(1e-4),
        origin_px: Some((1.0, 1.0)),
        ..PivRequest::default()
    };
    assert!(
        untimed
            .validate()
            .unwrap_err()
            .to_string()
            .contains("--fps or --log")
    );
    let missing = PivRequest {
        frames: "/nonexistent/frames".into(),
        ..PivRequest::default()
    };
    let e = run::run(&missing, &Silent).unwrap_err();
    assert!(
        matches!(e, FlowError::Input(_)) && e.to_string().starts_with("frames: "),
        "{e}"
    );
    let shear_with_shift = SyntheticRequest {
        field: SyntheticField::Shear,
        shift_px: Some((1.0, 0.0)),
        ..SyntheticRequest::default()
    };
    assert_eq!(
        shear_with_shift.validate().unwrap_err().to_string(),
        "--shift DX,DY is the motion of --field shift only"
    );
}

#[test]
fn synthetic_frames_render_on_demand_and_the_cone_has_its_foot() {
    let request = SyntheticRequest {
        field: SyntheticField::Cone,
        size_px: (64, 48),
        frames: 3,
        ..SyntheticRequest::default()
    };
    let outcome = piv_synthetic::run(&request, &Silent).unwrap();
    assert_eq!(outcome.len(), 3);
    let (a, b) = (outcome.frame(0).unwrap(), outcome.frame(1).unwrap());
    assert_eq!((a.width(), a.height()), (64, 48));
    assert_ne!(a, b, "the cone moves");
    assert_eq!(outcome.frame(1).unwrap(), b, "rendering is deterministic");
    let foot = outcome.foot_csv().unwrap();
    assert_eq!(foot.lines().count(), 1 + 3 * 4, "{foot}");
    assert!(
        outcome
            .settings_toml()
            .unwrap()
            .contains("field = \"Cone\"")
    );
}

#[test]
fn the_model_added_mass_grows_with_depth_and_the_foot_area() {
    let m = |r: f64, z: f64| sandjumper_flow::momentum::model_added_mass(0.57, r, z).unwrap();
    assert!(m(0.019, 0.02) > m(0.019, 0.01));
    assert!(m(0.038, 0.02) > m(0.019, 0.02));
    assert!(sandjumper_flow::momentum::model_added_mass(2.0, 0.019, 0.01).is_err());
}

#[test]
fn the_value_parsers_allow_what_the_requests_allow_with_the_command_lines_messages() {
    assert_eq!(run::parse_windows("64, 32,16").unwrap(), [64, 32, 16]);
    let e = run::parse_windows("64,x").unwrap_err();
    assert_eq!(
        e.to_string(),
        "--windows `64,x` is not a list of window sizes such as 64,32,16"
    );
    assert_eq!(e.blame(), Blame::Input);
    assert_eq!(run::parse_point("10, -2.5"), Ok((10.0, -2.5)));
    assert_eq!(
        run::parse_point("10"),
        Err("`10` is not a point X,Y in pixels".into())
    );
    assert_eq!(run::parse_ratio("1"), Ok(1.0));
    assert_eq!(
        run::parse_ratio("1.5"),
        Err("speed ratio 1.5 out of range (allowed: 0 to 1)".into())
    );
    assert_eq!(run::parse_sigma("0"), Ok(0.0));
    assert_eq!(
        run::parse_sigma("513"),
        Err("`513` is not a width in px (allowed: 0, off, or up to 512)".into())
    );
    assert_eq!(piv_synthetic::parse_shift("-3,1000"), Ok((-3.0, 1000.0)));
    assert_eq!(
        piv_synthetic::parse_shift("1001,0"),
        Err("`1001,0` is not a shift DX,DY in px (each within +-1000)".into())
    );
    assert_eq!(piv_synthetic::parse_size("16x16384"), Ok((16, 16384)));
    assert_eq!(
        piv_synthetic::parse_size("15x20"),
        Err("`15x20` is not a size WxH (16..=16384 px each)".into())
    );
}

/// `run_into` claims its folder once the arguments are checked and before any frame is
/// decoded: with frames that cannot be decoded and a folder that is not ours, the folder is
/// what is refused (as the command line always did); without a folder, the frames are.
#[test]
fn run_into_claims_the_folder_before_decoding_a_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    std::fs::create_dir(&frames).unwrap();
    for n in 0..2 {
        std::fs::write(frames.join(format!("frame_{n:06}.png")), b"not a png").unwrap();
    }
    let foreign = tmp.path().join("theirs");
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), b"someone else's folder").unwrap();
    let request = two_passes(&frames);
    let decode = run::run(&request, &Silent).unwrap_err().to_string();
    let folder = run::run_into(&request, &foreign, &Silent)
        .unwrap_err()
        .to_string();
    assert!(folder.contains("theirs"), "{folder}");
    assert_ne!(folder, decode);
    assert!(!decode.contains("theirs"), "{decode}");
}

/// A progress whose caller stops the run after `after` pairs.
struct StopAfter {
    after: u64,
    pairs: std::sync::Mutex<u64>,
}

impl sandjumper_output::Progress for StopAfter {
    fn advance(&self, n: u64) {
        *self.pairs.lock().unwrap() += n;
    }
    fn cancelled(&self) -> bool {
        *self.pairs.lock().unwrap() >= self.after
    }
}

#[test]
fn a_sequence_stopped_by_its_caller_stops_after_the_pair_it_was_on() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    synthetic(
        &frames,
        SyntheticField::Shift,
        (64, 64),
        6,
        Some((1.0, 0.5)),
    );
    let stop = StopAfter {
        after: 2,
        pairs: std::sync::Mutex::new(0),
    };
    let e = run::run(&two_passes(&frames), &stop).unwrap_err();
    assert_eq!(e.blame(), Blame::Internal, "{e}");
    assert!(e.to_string().contains("after 2 of 5 pairs"), "{e}");
    assert_eq!(*stop.pairs.lock().unwrap(), 2, "no pair after the stop");
}
