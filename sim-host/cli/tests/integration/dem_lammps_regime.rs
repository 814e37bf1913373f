//! `sandjumper dem lammps` in the paper's regime at reduced scale, against a sidewall: the
//! bed poured to the paper's loosest packing, a jump's push-off scaled to the foot at the
//! paper's Froude number, and the paper's sidewall PIV measured beside the exact 3-D column
//! of the same run.

use std::process::Command;

use crate::common;
use common::summary_json as summary;

/// The paper's regime at reduced scale against a sidewall: `--preset regime` poured to phi
/// 0.57 (rolling friction), a stutter's push-off at phi 0.57 from `jump` scaled to the 20 mm
/// foot at the paper's Froude number (`--scale-from-foot 0.076`), a half foot against a
/// frictional wall; the wall's grains rendered and run through the project's PIV beside the
/// exact column. Scaled down for the test: 2 mm grains (the pour table's) in a 40 x 40 x 30
/// mm bed.
#[test]
fn the_paper_regime_against_a_sidewall_measures_its_piv_beside_the_exact_column() {
    let Some(lmp) = common::lammps() else {
        return;
    };
    let work = tempfile::tempdir().unwrap();
    let jump = work.path().join("jump");
    let o = common::sandjumper(&[
        "jump",
        "--kind",
        "stutter",
        "--freq",
        "10",
        "--model",
        "eq4",
        "--phi",
        "0.57",
        "--out",
        jump.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = work.path().join("regime");
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(["dem", "lammps", "--preset", "regime", "--sidewall"])
        .args(["--grain-diameter", "0.002", "--bed-width", "0.04"])
        .args(["--bed-depth", "0.03", "--episode", "push-off"])
        .args(["--scale-from-foot", "0.076", "--ranks", "2", "--lmp"])
        .arg(&lmp)
        .arg("--trajectory")
        .arg(jump.join("trajectory.csv"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    let phi = s["settled_packing_fraction"].as_f64().unwrap();
    assert!((0.56..=0.58).contains(&phi), "settled at {phi}");
    // The push-off, scaled: its deepest point times 20/76.
    let push_off =
        sandjumper_dem::intruder::Trajectory::push_off_from_csv(&jump.join("trajectory.csv"))
            .unwrap();
    let sandjumper_dem::intruder::Trajectory::Table { depth_m, .. } = &push_off else {
        panic!("a table")
    };
    let deepest = depth_m.iter().copied().fold(f64::MIN, f64::max) * 0.020 / 0.076;
    let depth = s["max_depth_m"].as_f64().unwrap();
    assert!(
        (depth - deepest).abs() < 1e-6,
        "{depth} m, scaled {deepest} m"
    );
    // The sidewall PIV beside the exact column: pairs measured, their added masses within a
    // factor of 1.5 of each other (the half foot's column doubled: counted once, it would be
    // half the PIV's).
    assert!(s["sidewall_pairs"].as_u64().unwrap() >= 5, "{s}");
    let ratio = s["sidewall_piv_vs_exact_median"].as_f64().unwrap();
    assert!((0.67..=1.5).contains(&ratio), "PIV / exact {ratio}");
    assert!(s["column_lammps_vs_dumps_max_diff"].as_f64().unwrap() < 1e-7);
    let table = std::fs::read_to_string(out.join("sidewall.csv")).unwrap();
    assert!(table.starts_with("t_s,depth_m,foot_speed_m_s,exact_column_kg_m_s,piv_column_kg_m_s"));
}
