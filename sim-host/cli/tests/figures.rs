//! `sandjumper figures --quick`: every figure comes with its PNG, SVG and CSV, nothing failed
//! silently, the summary carries the numbers REPRODUCTION.md quotes, and a foreign directory
//! is never overwritten.

use std::process::Command;

const FIGURES: [&str; 6] = [
    "height_vs_phi",
    "height_vs_freq",
    "delayed_vs_tau",
    "penetration_force",
    "added_mass_stutter",
    "mechanism",
];

#[test]
fn quick_figures_write_png_svg_and_csv_for_every_figure() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("figs");
    let out = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(["figures", "--quick", "--out", out_dir.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for stem in FIGURES {
        for ext in ["png", "svg", "csv"] {
            let path = out_dir.join(format!("{stem}.{ext}"));
            let len = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
            assert!(
                len > 1000,
                "{} missing or nearly empty ({len} bytes)",
                path.display()
            );
        }
        let png = std::fs::read(out_dir.join(format!("{stem}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG", "{stem}.png is a PNG");
    }
    // One best row per (kind, model in eq1/eq4, phi) on the quick grid (6 phi), plus hard ground.
    let best = std::fs::read_to_string(out_dir.join("height_vs_phi.csv")).unwrap();
    assert_eq!(best.lines().count(), 1 + 3 * 2 * 6 + 3, "{best}");
    let failures = std::fs::read_to_string(out_dir.join("failures.csv")).unwrap();
    assert_eq!(failures.lines().count(), 1, "jumps failed:\n{failures}");
    let summary = std::fs::read_to_string(out_dir.join("summary.txt")).unwrap();
    for key in [
        "hard.single",
        "eq4.phi0.57.single",
        "eq4.single_phi0.57_over_hard",
        "mechanism.eq4",
    ] {
        assert!(summary.contains(key), "{key} not in summary:\n{summary}");
    }
    assert!(out_dir.join("params.toml").is_file());
}

#[test]
fn a_foreign_non_empty_directory_is_refused_with_status_2() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("thesis.tex"), "precious").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(["figures", "--quick", "--out", dir.path().to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("thesis.tex")).unwrap(),
        "precious"
    );
}

/// `figures dem` at a reduced scale (a 20 mm foot, the bed scaled with it; 1 mm grains kept):
/// every run's folder, the comparison's data, figures and parameters; the DEM's added mass
/// near eq. 6 with C scaled by R^2 for every paper-model run; PIV on the DEM's frames within
/// 20 % of the DEM's own; the grain momentum under the foot positive; bad input refused.
#[test]
fn figures_dem_reproduces_the_supplement_at_a_reduced_scale() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("dem");
    let out = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args([
            "figures",
            "dem",
            "--foot-width",
            "0.02",
            "--out",
            out_dir.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("[12/12]"), "{stderr}");
    for f in [
        "dem_runs.csv",
        "piv_vs_dem.csv",
        "momentum_vs_time.csv",
        "added_mass_and_momentum.png",
        "added_mass_and_momentum.svg",
        "sensitivity.png",
        "sensitivity.svg",
        "shear_bands.png",
        "shear_bands.svg",
        "figures_dem.toml",
        "summary.json",
    ] {
        assert!(out_dir.join(f).is_file(), "{f} missing");
    }
    for run in [
        "jump-single",
        "jump-stutter",
        "jump-delayed",
        "bed-0.70",
        "single",
        "stutter",
        "delayed",
        "piv-stutter",
        "bed-0.80",
        "stutter-0.80",
        "bed-full",
        "stutter-full",
    ] {
        assert!(
            out_dir.join("runs").join(run).is_dir(),
            "runs/{run} missing"
        );
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    let runs = s["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 5);
    for r in runs {
        let name = r["name"].as_str().unwrap();
        let ratio = r["added_mass_vs_eq6_median"].as_f64().unwrap();
        let p = r["grain_momentum_under_foot_kg_m_s"].as_f64().unwrap();
        assert!(p > 0.0, "{name}: peak momentum {p}");
        if name != "stutter-full" {
            assert!((0.6..1.7).contains(&ratio), "{name}: DEM / eq. 6 {ratio}");
        }
    }
    let piv = s["piv_over_dem_added_mass_median"].as_f64().unwrap();
    assert!((0.8..1.25).contains(&piv), "PIV / DEM {piv}");
    assert!(s["piv_pairs_compared"].as_u64().unwrap() >= 5);
    let toml = std::fs::read_to_string(out_dir.join("figures_dem.toml")).unwrap();
    assert!(toml.contains("foot_width_m = 0.02") && toml.contains("sandjumper dem intrude"));
    // The recorded commands and the runs' own records name the final folder, not the staging
    // one renamed at the end.
    assert!(!toml.contains(".partial"), "{toml}");
    let run_summary = std::fs::read_to_string(out_dir.join("runs/stutter/summary.json")).unwrap();
    assert!(!run_summary.contains(".partial"));
    let csv = std::fs::read_to_string(out_dir.join("dem_runs.csv")).unwrap();
    assert!(csv.contains("shear_band_left_deg") && csv.contains("window_depth_warning"));
    // The bed is deep enough for the push-off and the cone under it (a small foot's bed is
    // deeper than 1.6 widths).
    let bed_h: f64 = toml
        .lines()
        .find_map(|l| l.strip_prefix("bed_height_m = "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(bed_h > 1.6 * 0.02 + 0.003, "{bed_h}");
    // Bad input: exit 2 with what and what is allowed; nothing written.
    let bad = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args([
            "figures",
            "dem",
            "--foot-width",
            "0.5",
            "--out",
            dir.path().join("bad").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("0.005..=0.2"));
    assert!(!dir.path().join("bad").exists());
    // A frequency `jump` does not take is refused up front, with status 2.
    let bad = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(["figures", "dem", "--freq", "100", "--out"])
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("0.5..=40"));
}
