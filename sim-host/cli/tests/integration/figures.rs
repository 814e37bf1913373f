//! `sandjumper figures --quick`: every figure comes with its PNG, SVG and CSV, nothing failed
//! silently, the summary carries the numbers REPRODUCTION.md quotes, and a foreign directory
//! is never overwritten; `figures dem` refuses bad input with status 2.

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

/// `figures dem` refuses bad input with status 2, saying what and what is allowed, and writes
/// nothing: a foot out of range, a frequency `jump` does not take. (The run itself, at a
/// reduced scale, is tested in the library: `sim-host/figures-dem/tests/integration/reduced_scale.rs`.)
#[test]
fn figures_dem_refuses_bad_input_with_status_2() {
    let dir = tempfile::tempdir().unwrap();
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
    assert!(!dir.path().join("bad").exists());
}
