//! `figures dem` in the process, at a reduced scale: the typed outcome and the folder it
//! writes hold the supplement's claims.

use std::sync::Mutex;

use sandjumper_figures_dem::{FiguresDemRequest, run};
use sandjumper_output::Progress;

/// The notes a run gives, kept.
#[derive(Default)]
struct Notes(Mutex<Vec<String>>);

impl Progress for Notes {
    fn note(&self, line: &str) {
        self.0.lock().unwrap().push(line.to_string());
    }
}

/// The foot of the reduced scale, m.
const FOOT_M: f64 = 0.01;

/// `figures dem` at a reduced scale: a 10 mm foot (the bed scaled with it; 1.0/1.4 mm grains
/// kept), the full model's bed settled for 0.1 simulated s instead of up to `dem bed`'s 2
/// (its row is checked for its momentum and its folder, not against eq. 6). Every run's
/// folder; the comparison's data, figures and parameters; the DEM's added mass near eq. 6
/// (0.6..1.7 of it, C scaled by R^2) for every paper-model run; PIV on the DEM's frames within
/// 20 % of the DEM's own over at least 5 pairs; the grain momentum under the foot positive in
/// every run; the recorded commands naming the final folder.
///
/// Full scale is the robot's 76 mm foot, the bed 4 widths wide and 1.6 deep, every bed up to
/// 2 s: `sandjumper figures dem --out DIR` (REPRODUCTION.md section 7, docs/dem.md; about 8 min
/// on 2 cores). The command line's test of it (`cli/tests/integration/figures.rs`) ran a 20 mm foot.
#[test]
fn figures_dem_reproduces_the_supplement_at_a_reduced_scale() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("dem");
    let request = FiguresDemRequest {
        out: out_dir.clone(),
        foot_width_m: FOOT_M,
        bed_max_time_s: 0.1,
        ..FiguresDemRequest::default()
    };
    let notes = Notes::default();
    let outcome = run(&request, &notes).unwrap();
    let notes = notes.0.into_inner().unwrap();
    assert!(
        notes.iter().any(|n| n.starts_with("figures dem [12/12] ")),
        "{notes:#?}"
    );
    assert_eq!(outcome.out, out_dir);
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
    // The outcome's rows, as summary.json holds them.
    let names: Vec<&str> = outcome.runs.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "single",
            "stutter",
            "delayed",
            "stutter-0.80",
            "stutter-full"
        ]
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(
        summary["runs"],
        serde_json::to_value(&outcome.runs).unwrap()
    );
    assert_eq!(
        summary["piv_over_dem_added_mass_median"].as_f64(),
        Some(outcome.piv_over_dem_added_mass_median)
    );
    for r in &outcome.runs {
        let (ratio, p) = (
            r.added_mass_vs_eq6_median,
            r.grain_momentum_under_foot_kg_m_s,
        );
        assert!(p > 0.0, "{}: peak momentum {p}", r.name);
        if r.name != "stutter-full" {
            assert!(
                (0.6..1.7).contains(&ratio),
                "{}: DEM / eq. 6 {ratio}",
                r.name
            );
        }
    }
    let piv = outcome.piv_over_dem_added_mass_median;
    assert!((0.8..1.25).contains(&piv), "PIV / DEM {piv}");
    assert!(
        outcome.piv_pairs_compared >= 5,
        "{}",
        outcome.piv_pairs_compared
    );
    let toml = std::fs::read_to_string(out_dir.join("figures_dem.toml")).unwrap();
    assert!(
        toml.contains(&format!("foot_width_m = {FOOT_M}"))
            && toml.contains("sandjumper dem intrude")
            && toml.contains("--max-time 0.1"),
        "{toml}"
    );
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
    assert!(bed_h > 1.6 * FOOT_M + 0.003, "{bed_h}");
}
