//! `fit drag` (alpha, eq1) and `fit inertial` (b, eq4): jump heights simulated with known
//! drag parameters plus seeded noise are fitted back per packing fraction through the real
//! simulator; the params files per phi read back; bad jump files are refused clearly.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use sandjumper_model::{JumpKind, JumpSpec, ModelName, Params, SimOptions, simulate_jump};
use sandjumper_study::fit::data::HeightColumn;
use sandjumper_study::fit::jumps::{DragParam, JumpFitSetup, fit_jumps_file};
use sandjumper_study::fit::{FitError, FitReport, write_params_files};

fn gaussian(rng: &mut StdRng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

fn kind_name(kind: JumpKind) -> &'static str {
    match kind {
        JumpKind::Single => "single",
        JumpKind::Stutter => "stutter",
        JumpKind::DelayedStutter => "delayed",
    }
}

fn sim() -> SimOptions {
    SimOptions {
        rtol: 1e-9,
        ..SimOptions::default()
    }
}

/// Simulated "measurements": each (phi, kind, f, tau) jumped on `params(phi)`, plus noise of
/// `sigma_m` (camera tracking), as a sweep.csv-like file with an extra column.
fn measured(
    dir: &Path,
    model: ModelName,
    jumps: &[(f64, JumpKind, f64, f64)],
    params: impl Fn(f64) -> Params,
    sigma_m: f64,
) -> PathBuf {
    let mut rng = StdRng::seed_from_u64(5);
    let mut text = String::from("kind,model,phi,freq_hz,tau_s,jump_height_m,max_depth_m\n");
    for &(phi, kind, freq_hz, tau_s) in jumps {
        let spec = JumpSpec {
            kind,
            freq_hz,
            tau_s,
            model,
        };
        let s = simulate_jump(&params(phi), &spec, &sim()).unwrap().summary;
        let h = s.jump_height_m + sigma_m * gaussian(&mut rng);
        let _ = writeln!(
            text,
            "{},{model},{phi},{freq_hz},{tau_s},{h},{}",
            kind_name(kind),
            s.max_depth_m
        );
    }
    let path = dir.join("jumps.csv");
    std::fs::write(&path, text).unwrap();
    path
}

fn preset(phi: f64) -> Result<Params, String> {
    Params::preset(phi).map_err(|e| e.to_string())
}

fn fitted(report: &FitReport, phi: f64) -> (f64, f64) {
    let f = report
        .fits
        .iter()
        .find(|f| f.phi == Some(phi))
        .expect("a fit for phi");
    (f.value, f.stderr)
}

#[test]
fn drag_alpha_per_phi_is_recovered_from_single_jump_heights() {
    let dir = tempfile::tempdir().unwrap();
    // True alphas differ from the presets (60 and 90 kg/m), where the fit starts.
    let truth = |phi: f64| if phi < 0.59 { 85.0 } else { 120.0 };
    let jumps: Vec<_> = [0.58, 0.60]
        .into_iter()
        .flat_map(|phi| {
            [6.0, 7.5, 9.0, 10.5, 12.0, 13.5, 15.0, 16.5].map(|f| (phi, JumpKind::Single, f, 0.0))
        })
        .chain([(0.58, JumpKind::Stutter, 8.0, 0.0)]) // not a single jump: left out
        .collect();
    let params = |phi: f64| {
        let mut p = Params::preset(phi).unwrap();
        p.sand.alpha_kg_m = truth(phi);
        p
    };
    let path = measured(dir.path(), ModelName::Eq1, &jumps, params, 0.5e-3);
    let setup = JumpFitSetup {
        param: DragParam::Alpha,
        model: ModelName::Eq1,
        height: HeightColumn::Jump,
        sim: sim(),
        base: &preset,
    };
    let report = fit_jumps_file(&path, &setup).unwrap();
    assert_eq!(report.points_excluded, 1, "{}", report.summary());
    for phi in [0.58, 0.60] {
        let (v, se) = fitted(&report, phi);
        let t = truth(phi);
        assert!(
            (v - t).abs() < 0.15 * t,
            "phi {phi}: alpha {v} ± {se} vs {t}\n{}",
            report.summary()
        );
        assert!(
            (v - t).abs() < 3.0 * se,
            "phi {phi}: true {t} outside 3 stderr of {v} ± {se}"
        );
    }
    assert!(report.residual_rms < 1.5e-3, "{}", report.summary());

    // Two packing fractions: one params file per phi, each a valid override.
    let written = write_params_files(&report, &dir.path().join("drag.toml")).unwrap();
    let names: Vec<String> = written
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into())
        .collect();
    assert_eq!(names, ["drag.phi-0.580.toml", "drag.phi-0.600.toml"]);
    for (path, phi) in written.iter().zip([0.58, 0.60]) {
        let p = Params::preset(phi)
            .unwrap()
            .with_overrides_toml(&std::fs::read_to_string(path).unwrap(), "x")
            .unwrap();
        assert_eq!(p.sand.alpha_kg_m, fitted(&report, phi).0);
    }
}

#[test]
fn inertial_b_is_recovered_from_all_jump_kinds() {
    let dir = tempfile::tempdir().unwrap();
    let (phi, b_true) = (0.59, 40.0); // preset b = 25
    let jumps = [
        (phi, JumpKind::Single, 8.0, 0.0),
        (phi, JumpKind::Single, 12.0, 0.0),
        (phi, JumpKind::Stutter, 6.0, 0.0),
        (phi, JumpKind::DelayedStutter, 8.0, 0.3),
        (phi, JumpKind::DelayedStutter, 10.0, 0.5),
    ];
    let params = |phi: f64| {
        let mut p = Params::preset(phi).unwrap();
        p.sand.added_mass_drag_b = b_true;
        p
    };
    let path = measured(dir.path(), ModelName::Eq4, &jumps, params, 0.3e-3);
    let setup = JumpFitSetup {
        param: DragParam::B,
        model: ModelName::Eq4,
        height: HeightColumn::Jump,
        sim: sim(),
        base: &preset,
    };
    let report = fit_jumps_file(&path, &setup).unwrap();
    let (v, se) = fitted(&report, phi);
    assert!(
        (v - b_true).abs() < 0.2 * b_true,
        "b {v} ± {se}\n{}",
        report.summary()
    );
    assert!(
        (v - b_true).abs() < 3.0 * se,
        "true {b_true} outside 3 stderr of {v} ± {se}"
    );
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    assert_eq!(json["fits"][0]["param"], "b");
    assert_eq!(json["fits"][0]["phi"], phi);
}

fn jump_error(text: &str, param: DragParam, model: ModelName) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("jumps.csv");
    std::fs::write(&path, text).unwrap();
    let setup = JumpFitSetup {
        param,
        model,
        height: HeightColumn::Jump,
        sim: sim(),
        base: &preset,
    };
    match fit_jumps_file(&path, &setup) {
        Err(e @ (FitError::Data(_) | FitError::Fit(_))) => e.to_string(),
        other => panic!("expected an error, got {other:?}"),
    }
}

#[test]
fn bad_jump_files_are_refused_with_line_and_reason() {
    let header = "kind,phi,freq_hz,tau_s,jump_height_m\n";
    let e = jump_error(
        "kind,phi,freq_hz,jump_height_m\nsingle,0.58,8,0.05\n",
        DragParam::Alpha,
        ModelName::Eq1,
    );
    assert!(e.contains("missing column `tau_s`"), "{e}");
    let e = jump_error(
        &format!("{header}single,0.58,8,0,0.05\nhop,0.58,9,0,0.05\n"),
        DragParam::Alpha,
        ModelName::Eq1,
    );
    assert!(
        e.contains(":3:") && e.contains("unknown jump kind `hop`"),
        "{e}"
    );
    let e = jump_error(
        &format!("{header}single,0.58,8,0,0.05\nsingle,0.60,9,0,0.05\nsingle,0.60,10,0,0.06\n"),
        DragParam::Alpha,
        ModelName::Eq1,
    );
    assert!(e.contains("phi = 0.58: 1 jump(s); at least 2"), "{e}");
    let e = jump_error(
        &format!("{header}stutter,0.58,8,0,0.05\nstutter,0.58,9,0,0.05\n"),
        DragParam::Alpha,
        ModelName::Eq1,
    );
    assert!(e.contains("no single jumps"), "{e}");
    let e = jump_error(
        &format!("{header}single,0.58,-8,0,0.05\n"),
        DragParam::Alpha,
        ModelName::Eq1,
    );
    assert!(e.contains(":2:") && e.contains("freq_hz = -8"), "{e}");
    let e = jump_error(
        &format!("{header}single,0.58,8,0,0.05\nsingle,0.58,9,0,0.05\n"),
        DragParam::Alpha,
        ModelName::Eq4,
    );
    assert!(e.contains("--model eq4 has no alpha"), "{e}");
    let e = jump_error(
        &format!("{header}single,0.58,8,0,0.05\nsingle,0.58,9,0,0.05\n"),
        DragParam::B,
        ModelName::Eq1,
    );
    assert!(e.contains("--model eq1 has no b"), "{e}");
    // A phi without preset (and no params file) names the phi and the row.
    let e = jump_error(
        &format!("{header}single,0.50,8,0,0.05\nsingle,0.50,9,0,0.05\n"),
        DragParam::Alpha,
        ModelName::Eq1,
    );
    assert!(e.contains(":2:") && e.contains("phi = 0.5"), "{e}");
}
