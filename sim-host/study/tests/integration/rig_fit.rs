//! `fit intrusion` recovers the simulated sand from what the rig tool measures: the slow
//! intrusion through the simulated rig (`sandjumper_rig::tool::intrude`, sil, the `eq1` sand:
//! two-resistance `F_p` with k1 1600 N/m, k2 1100 N/m, delta 15 mm at phi 0.57, and the
//! re-intrusion overshoot with kappa 1600 N/m, l_re 5 mm), its curves written as the command
//! writes them and fitted as `fit intrusion --first` / `--reintrusion` fits them.
//!
//! Tolerances: k1, k2 and delta within 3 % (the measurement is quasi-static; what is left is
//! the 0.25 mm binning and the 1 um encoder); kappa and l_re within 25 % (a 5 mm decay sampled
//! in 0.25 mm bins behind the position loop's lag).

#![cfg(feature = "rig")]

use sandjumper_model::params::ModelName;
use sandjumper_output::{Silent, StagedDir};
use sandjumper_rig::tool::intrude::{self, IntrudeRequest};
use sandjumper_study::fit::intrusion::CurveKind;
use sandjumper_study::fit::{self, FitKind, FitReport, FitRequest};

fn fitted(report: &FitReport, name: &str) -> f64 {
    report
        .fits
        .iter()
        .find(|f| f.param == name)
        .unwrap_or_else(|| panic!("no {name} in {:?}", report.fits))
        .value
}

/// The rig's first intrusion gives back k1, k2 and delta within 3 %, its re-intrusion kappa
/// and l_re within 25 % (the rig tool's defaults: 20 mm at 10 mm/s, holds of 0.5 s,
/// re-intrusion to 30 mm).
#[test]
fn intrusion_through_the_rig_and_fit_recover_the_sand() {
    let eq1_sand = IntrudeRequest {
        model: ModelName::Eq1,
        ..IntrudeRequest::default()
    };
    let measured = intrude::run(&eq1_sand, &Silent).expect("the intrusion runs");
    assert!(measured.completed, "{:?}", measured.faults);
    // Its curves as `rig intrude --out` writes them, `fit intrusion`'s input.
    let folder = tempfile::tempdir().unwrap();
    let staged = StagedDir::create(&folder.path().join("intrude")).unwrap();
    let out = measured.write(staged, false).unwrap();
    let fit_curve = |file: &str, curve: CurveKind| {
        fit::run(
            &FitRequest {
                file: out.join(file),
                kind: FitKind::Intrusion {
                    curve,
                    z_start_m: None,
                },
                ..FitRequest::default()
            },
            &Silent,
        )
        .expect("the fit converges")
    };
    let first = fit_curve("intrusion.csv", CurveKind::First);
    for (name, truth) in [("k1", 1600.0), ("k2", 1100.0), ("delta", 0.015)] {
        let v = fitted(&first, name);
        assert!(
            (v / truth - 1.0).abs() < 0.03,
            "{name} = {v}, sand has {truth}"
        );
    }
    let re = fit_curve("reintrusion.csv", CurveKind::Re);
    for (name, truth) in [("kappa", 1600.0), ("l_re", 0.005)] {
        let v = fitted(&re, name);
        assert!(
            (v / truth - 1.0).abs() < 0.25,
            "{name} = {v}, sand has {truth}"
        );
    }
}
