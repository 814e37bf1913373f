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

/// `sandjumper figures` with `options` into a new folder, which must succeed: the folder's
/// holder (removed when dropped) and the output's path.
fn figures(options: &[&str]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("figs");
    let mut args = vec!["figures"];
    args.extend_from_slice(options);
    args.extend(["--out", out_dir.to_str().unwrap()]);
    let out = crate::common::sandjumper(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (dir, out_dir)
}

#[test]
fn quick_figures_write_png_svg_and_csv_for_every_figure() {
    let (_dir, out_dir) = figures(&["--quick"]);
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

/// The full `sandjumper figures` set (~45 s) regenerates the summary committed beside
/// REPRODUCTION.md (`docs/reproduction/figures-summary.txt`) to the last digit, and every
/// height REPRODUCTION.md's sections 1-6 quote with its frequency (`49.9 mm @ 12.8 Hz`) is one
/// of that summary's: a model change that moves a number fails here until both are
/// regenerated (`sandjumper figures --out DIR`, then copy `DIR/summary.txt` there).
#[test]
fn the_full_figures_regenerate_the_committed_summary_and_the_heights_reproduction_quotes() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let (_dir, out_dir) = figures(&[]);
    let summary = std::fs::read_to_string(out_dir.join("summary.txt")).unwrap();
    let committed =
        std::fs::read_to_string(root.join("docs/reproduction/figures-summary.txt")).unwrap();
    assert!(
        summary == committed,
        "the figures' summary is not the committed one: regenerate it (sandjumper figures --out \
         DIR; cp DIR/summary.txt docs/reproduction/figures-summary.txt) and REPRODUCTION.md's \
         numbers with it"
    );
    // "H mm at F Hz" in the summary, to REPRODUCTION.md's one decimal.
    let mut heights = std::collections::HashSet::new();
    for line in summary.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        for w in words.windows(5) {
            let unit = w[4].trim_end_matches([')', ';', ',', '.']);
            if w[1] == "mm"
                && w[2] == "at"
                && unit == "Hz"
                && let (Ok(h), Ok(f)) = (w[0].parse::<f64>(), w[3].parse::<f64>())
            {
                heights.insert(format!("{h:.1} mm @ {f:.1} Hz"));
            }
        }
    }
    let text = std::fs::read_to_string(root.join("REPRODUCTION.md")).unwrap();
    let sections = text.split("## 7.").next().unwrap();
    let mut quoted = 0;
    for (i, _) in sections.match_indices(" mm @ ") {
        let before = sections[..i]
            .rsplit(|c: char| c.is_whitespace() || c == '|')
            .next();
        let after = sections[i + 6..].split(" Hz").next();
        let (Some(h), Some(f)) = (before, after) else {
            continue;
        };
        let (Ok(h), Ok(f)) = (h.parse::<f64>(), f.parse::<f64>()) else {
            continue;
        };
        let q = format!("{h:.1} mm @ {f:.1} Hz");
        assert!(
            heights.contains(&q),
            "REPRODUCTION.md quotes {q}, not in the summary"
        );
        quoted += 1;
    }
    assert!(quoted >= 10, "{quoted} heights quoted");
}
