//! `fit intrusion` and `fit added-mass`: curves generated from the model with known
//! parameters plus seeded Gaussian noise are fitted back within stated tolerances, the true
//! value lies within 3 standard errors, the written params file reads back as parameters;
//! bad or insufficient data give an error naming the file, line and problem.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use sandjumper_model::Params;
use sandjumper_study::fit::added_mass::fit_added_mass_file;
use sandjumper_study::fit::intrusion::{CurveKind, fit_intrusion_file};
use sandjumper_study::fit::{FitError, FitReport, write_params_files};

/// Standard normal sample (Box-Muller) from a seeded generator.
fn gaussian(rng: &mut StdRng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// Two-resistance law, written out independently of the library as the test's oracle.
fn two_resistance(k1: f64, k2: f64, delta: f64, z: f64) -> f64 {
    if z <= delta {
        k1 * z
    } else {
        k1 * delta + k2 * (z - delta)
    }
}

fn write_csv(dir: &Path, name: &str, header: &str, rows: &[(f64, f64)]) -> PathBuf {
    let mut text = format!("{header}\n");
    for (a, b) in rows {
        let _ = writeln!(text, "{a:.7},{b:.7}");
    }
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn value(report: &FitReport, param: &str) -> (f64, f64) {
    let f = report
        .fits
        .iter()
        .find(|f| f.param == param)
        .unwrap_or_else(|| panic!("no {param}"));
    (f.value, f.stderr)
}

/// `fitted` within `rel` of `truth`, and `truth` within 3 standard errors.
fn assert_recovered(report: &FitReport, param: &str, truth: f64, rel: f64) {
    let (v, se) = value(report, param);
    assert!(
        (v - truth).abs() <= rel * truth,
        "{param} = {v} (± {se}) not within {rel} of {truth}\n{}",
        report.summary()
    );
    assert!(
        (v - truth).abs() <= 3.0 * se,
        "{param}: true {truth} outside 3 stderr of {v} ± {se}\n{}",
        report.summary()
    );
    assert!(
        se > 0.0 && se < 0.2 * truth,
        "{param}: stderr {se} implausible for {v}"
    );
}

/// A slow first intrusion to 5 cm, 200 samples, force noise `sigma_n` (motor-current noise).
fn first_intrusion(k1: f64, k2: f64, delta: f64, sigma_n: f64, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..200)
        .map(|i| {
            let z = 0.05 * f64::from(i) / 199.0;
            (
                z,
                two_resistance(k1, k2, delta, z) + sigma_n * gaussian(&mut rng),
            )
        })
        .collect()
}

#[test]
fn first_intrusion_recovers_k1_k2_delta_at_low_and_high_packing() {
    let dir = tempfile::tempdir().unwrap();
    let params = Params::default();
    // (k1, k2, delta): the phi = 0.57 and phi = 0.62 presets of docs/model.md.
    for (i, (k1, k2, delta)) in [(1600.0, 1100.0, 0.015), (10_000.0, 2500.0, 0.010)]
        .into_iter()
        .enumerate()
    {
        let f_max = two_resistance(k1, k2, delta, 0.05);
        let rows = first_intrusion(k1, k2, delta, 0.01 * f_max, 7 + i as u64);
        let path = write_csv(
            dir.path(),
            &format!("first{i}.csv"),
            "depth_m,force_n",
            &rows,
        );
        let report = fit_intrusion_file(&path, CurveKind::Auto, &params, None).unwrap();
        assert!(
            report.notes[0].contains("first intrusion"),
            "{:?}",
            report.notes
        );
        assert_recovered(&report, "k1", k1, 0.03);
        assert_recovered(&report, "k2", k2, 0.03);
        assert_recovered(&report, "delta", delta, 0.08);
        // Residual RMS is the noise level.
        assert!(
            (report.residual_rms / (0.01 * f_max) - 1.0).abs() < 0.15,
            "{}",
            report.residual_rms
        );

        // The params file is accepted as an override and carries the fitted values.
        let out = dir.path().join(format!("first{i}.toml"));
        let written = write_params_files(&report, &out).unwrap();
        assert_eq!(written, vec![out.clone()]);
        let text = std::fs::read_to_string(&out).unwrap();
        let fitted = Params::default()
            .with_overrides_toml(&text, "fit.toml")
            .unwrap();
        assert_eq!(fitted.sand.k1_n_m, value(&report, "k1").0);
        assert_eq!(fitted.sand.k2_n_m, value(&report, "k2").0);
        assert_eq!(fitted.sand.delta_m, value(&report, "delta").0);
    }
}

#[test]
fn reintrusion_overshoot_recovers_kappa_and_l_re() {
    let dir = tempfile::tempdir().unwrap();
    let params = Params::preset(0.57).unwrap();
    let (k1, k2, delta) = (params.sand.k1_n_m, params.sand.k2_n_m, params.sand.delta_m);
    let (z_start, kappa, l_re) = (0.02, 2.0 * k1, 0.004);
    let mut rng = StdRng::seed_from_u64(11);
    let rows: Vec<(f64, f64)> = (0..150)
        .map(|i| {
            let z = z_start + 0.025 * f64::from(i) / 149.0;
            let f =
                two_resistance(k1, k2, delta, z) + kappa * z_start * (-(z - z_start) / l_re).exp();
            (z, f + 0.3 * gaussian(&mut rng))
        })
        .collect();
    let path = write_csv(dir.path(), "re.csv", "depth_m,force_n", &rows);
    let report = fit_intrusion_file(&path, CurveKind::Auto, &params, None).unwrap();
    assert!(
        report.notes[0].contains("re-intrusion (auto-detected"),
        "{:?}",
        report.notes
    );
    assert_recovered(&report, "kappa", kappa, 0.05);
    assert_recovered(&report, "l_re", l_re, 0.08);
    let out = dir.path().join("re.toml");
    write_params_files(&report, &out).unwrap();
    let fitted = params
        .clone()
        .with_overrides_toml(&std::fs::read_to_string(&out).unwrap(), "re.toml")
        .unwrap();
    assert!((fitted.sand.reintrusion_kappa_per_k1 - value(&report, "kappa").0 / k1).abs() < 1e-12);
    assert_eq!(fitted.sand.reintrusion_length_m, value(&report, "l_re").0);
}

/// docs/model.md's m_a(s), written out as the test's oracle.
fn added_mass(p: &Params, mu: f64, c: f64, s: f64) -> f64 {
    let (r, tan) = (
        p.robot.foot_radius_m,
        p.sand.shear_band_angle_deg.to_radians().tan(),
    );
    let sc = s.min(r * tan / mu);
    let cone = sc * (r * r + (mu * sc).powi(2) / (3.0 * tan * tan) - r * mu * sc / tan);
    p.sand.packing_fraction
        * p.sand.grain_density_kg_m3
        * mu
        * std::f64::consts::PI
        * (cone + c * s)
}

/// A PIV-like added-mass curve to 4 cm: 5 % multiplicative noise, and over the deepest 10 %
/// of the stroke the foot slows to rest so `P / v` blows up (the singular end).
fn piv_curve(p: &Params, mu: f64, c: f64, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = StdRng::seed_from_u64(seed);
    let s_max = 0.04;
    (1..=120)
        .map(|i| {
            let s = s_max * f64::from(i) / 120.0;
            let slowing = ((s_max - s) / (0.1 * s_max)).clamp(0.02, 1.0);
            (
                s,
                added_mass(p, mu, c, s) * (1.0 + 0.05 * gaussian(&mut rng)) / slowing,
            )
        })
        .collect()
}

#[test]
fn added_mass_recovers_mu_and_c_when_the_singular_end_is_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let params = Params::preset(0.57).unwrap();
    let (mu, c) = (2.0, 8e-4);
    let path = write_csv(
        dir.path(),
        "ma.csv",
        "depth_m,added_mass_kg",
        &piv_curve(&params, mu, c, 3),
    );
    let report = fit_added_mass_file(&path, &params, 0.15).unwrap();
    assert_recovered(&report, "mu", mu, 0.10);
    assert_recovered(&report, "C", c, 0.15);
    assert_eq!(
        report.points_excluded, 18,
        "deepest 15 % of 120 evenly spaced points"
    );
    assert!(
        report
            .notes
            .iter()
            .any(|n| n.contains("singular low-speed end"))
    );

    // Keeping the singular end biases the fit far outside its error bars: the rule matters.
    // Keeping the singular end either wrecks the fit (a parameter runs off and is reported
    // undetermined) or biases it far outside its error bars: the exclusion rule matters.
    match fit_added_mass_file(&path, &params, 0.0) {
        Ok(b) => {
            let (v, se) = value(&b, "C");
            assert!(
                (v - c).abs() > 3.0 * se,
                "with the singular end C = {v} ± {se} still fits {c}"
            );
        }
        Err(e) => assert!(e.to_string().contains("do not determine"), "{e}"),
    }
}

#[test]
fn json_has_the_documented_shape() {
    let dir = tempfile::tempdir().unwrap();
    let rows = first_intrusion(1600.0, 1100.0, 0.015, 0.5, 1);
    let path = write_csv(dir.path(), "f.csv", "depth_m,force_n", &rows);
    let report = fit_intrusion_file(&path, CurveKind::First, &Params::default(), None).unwrap();
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    let fits = json["fits"].as_array().unwrap();
    let names: Vec<&str> = fits.iter().map(|f| f["param"].as_str().unwrap()).collect();
    assert_eq!(names, ["k1", "k2", "delta"]);
    for f in fits {
        assert!(f["phi"].is_null(), "intrusion laws are not per-phi: {f}");
        assert!(f["value"].as_f64().unwrap() > 0.0 && f["stderr"].as_f64().unwrap() > 0.0);
    }
    assert!((json["residual_rms"].as_f64().unwrap() - report.residual_rms).abs() < 1e-15);
}

fn data_error(text: &str, kind: CurveKind) -> (String, Option<u64>) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.csv");
    std::fs::write(&path, text).unwrap();
    match fit_intrusion_file(&path, kind, &Params::default(), None) {
        Err(FitError::Data(e)) => {
            assert_eq!(e.path, path, "the error names the file");
            (e.problem, e.line)
        }
        other => panic!("expected a data error for {text:?}, got {other:?}"),
    }
}

fn good_rows(n: usize) -> String {
    (0..n)
        .map(|i| format!("{},{}\n", 0.001 * i as f64, 2.0 * i as f64))
        .collect()
}

#[test]
fn bad_intrusion_data_are_refused_with_file_line_and_problem() {
    let (p, line) = data_error(
        &format!("depth,force_n\n{}", good_rows(10)),
        CurveKind::First,
    );
    assert!(p.contains("missing column `depth_m`"), "{p}");
    assert_eq!(line, Some(1));

    let (p, line) = data_error(
        &format!("depth_m,force_n\n{}0.02,NaN\n", good_rows(10)),
        CurveKind::First,
    );
    assert!(p.contains("`NaN` is not a finite number"), "{p}");
    assert_eq!(line, Some(12));

    let (p, line) = data_error(
        &format!("depth_m,force_n\n{}0.004,30\n", good_rows(10)),
        CurveKind::First,
    );
    assert!(p.contains("does not increase"), "{p}");
    assert_eq!(line, Some(12));

    let (p, line) = data_error("depth_m,force_n\n0,0\n0.001,abc\n", CurveKind::First);
    assert!(p.contains("`abc` is not a number"), "{p}");
    assert_eq!(line, Some(3));

    let (p, _) = data_error(
        &format!("depth_m,force_n\n{}", good_rows(5)),
        CurveKind::First,
    );
    assert!(p.contains("5 data rows; at least 8"), "{p}");

    let zeros: String = (0..20)
        .map(|i| format!("{},0\n", 0.001 * f64::from(i)))
        .collect();
    let (p, _) = data_error(&format!("depth_m,force_n\n{zeros}"), CurveKind::First);
    assert!(p.contains("zero on every row"), "{p}");

    let (p, line) = data_error(
        &format!("depth_m,force_n\n-0.001,0\n{}", good_rows(10)),
        CurveKind::First,
    );
    assert!(p.contains("negative"), "{p}");
    assert_eq!(line, Some(2));

    // A re-intrusion curve that never exceeds the first-intrusion law has no overshoot.
    let flat: String = (0..20)
        .map(|i| format!("{},1\n", 0.02 + 0.001 * f64::from(i)))
        .collect();
    let (p, _) = data_error(&format!("depth_m,force_n\n{flat}"), CurveKind::Re);
    assert!(p.contains("no overshoot"), "{p}");
}

#[test]
fn a_missing_file_is_an_error_not_a_panic() {
    let err = fit_intrusion_file(
        Path::new("/nonexistent/curve.csv"),
        CurveKind::Auto,
        &Params::default(),
        None,
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .starts_with("/nonexistent/curve.csv: cannot read the file"),
        "{err}"
    );
}

#[test]
fn added_mass_exclusion_that_leaves_too_few_points_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let params = Params::default();
    let rows: Vec<(f64, f64)> = (1..=8)
        .map(|i| {
            (
                0.005 * f64::from(i),
                added_mass(&params, 2.0, 8e-4, 0.005 * f64::from(i)),
            )
        })
        .collect();
    let path = write_csv(dir.path(), "ma.csv", "depth_m,added_mass_kg", &rows);
    let err = fit_added_mass_file(&path, &params, 0.9).unwrap_err();
    assert!(
        err.to_string()
            .contains("points left after excluding the deepest 90%"),
        "{err}"
    );
    let err = fit_added_mass_file(&path, &params, 1.5).unwrap_err();
    assert!(
        err.to_string().contains("allowed 0 <= fraction < 1"),
        "{err}"
    );
}
