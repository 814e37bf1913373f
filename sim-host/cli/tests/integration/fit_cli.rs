//! `sandjumper fit` on the command line: a fit's params file is accepted by `--params`, the
//! JSON has the documented shape, bad data and bad options exit with status 2 and one clear
//! message naming the file and line.

use std::fmt::Write as _;
use std::path::Path;

use crate::common;
use common::{refused, sandjumper};

fn write_intrusion(path: &Path) {
    // Noise-free two-resistance curve plus a small deterministic wiggle (k1 1600, k2 1100,
    // delta 15 mm).
    let mut text = String::from("depth_m,force_n\n");
    for i in 0..100 {
        let z = 0.0005 * f64::from(i);
        let f = if z <= 0.015 {
            1600.0 * z
        } else {
            24.0 + 1100.0 * (z - 0.015)
        };
        let _ = writeln!(text, "{z},{}", f + 0.2 * (f64::from(i) * 1.7).sin());
    }
    std::fs::write(path, text).unwrap();
}

#[test]
fn intrusion_fit_writes_a_params_file_the_cli_accepts() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("intrusion.csv");
    write_intrusion(&csv);
    let toml = dir.path().join("sand.toml");
    let out = sandjumper(&[
        "fit",
        "intrusion",
        csv.to_str().unwrap(),
        "--out",
        toml.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let k1 = json["fits"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["param"] == "k1")
        .unwrap();
    assert!(
        (k1["value"].as_f64().unwrap() - 1600.0).abs() < 20.0,
        "{json}"
    );
    assert!(k1["phi"].is_null());
    assert!(json["residual_rms"].as_f64().unwrap() < 0.3);

    let params = sandjumper(&["params", "--params", toml.to_str().unwrap()]);
    assert!(
        params.status.success(),
        "{}",
        String::from_utf8_lossy(&params.stderr)
    );
    let text = String::from_utf8(params.stdout).unwrap();
    let resolved: toml::Table = text.parse().unwrap();
    let k1_written = resolved["sand"]["k1_n_m"].as_float().unwrap();
    assert_eq!(k1_written, k1["value"].as_f64().unwrap());

    // The human summary names each parameter with its interval.
    let human = sandjumper(&["fit", "intrusion", csv.to_str().unwrap()]);
    let s = String::from_utf8(human.stdout).unwrap();
    assert!(
        s.contains("k1") && s.contains("95% CI") && s.contains("residual RMS"),
        "{s}"
    );
}

#[test]
fn bad_data_and_options_exit_with_status_2() {
    let dir = tempfile::tempdir().unwrap();
    let nan = dir.path().join("nan.csv");
    std::fs::write(&nan, "depth_m,force_n\n0,0\n0.001,1.6\n0.002,nan\n").unwrap();
    let p = nan.to_str().unwrap();
    refused(
        &["fit", "intrusion", p],
        &[&format!("{p}:4:"), "not a finite number"],
    );
    refused(
        &["fit", "intrusion", "/nonexistent.csv"],
        &["/nonexistent.csv", "cannot read"],
    );
    refused(
        &["fit", "added-mass", p, "--exclude-deepest", "1.5"],
        &["allowed 0 <= fraction < 1"],
    );
    let jumps = dir.path().join("jumps.csv");
    std::fs::write(
        &jumps,
        "kind,phi,freq_hz,tau_s,jump_height_m\nsingle,0.58,8,0,0.05\nsingle,0.58,9,0,0.05\n",
    )
    .unwrap();
    refused(
        &["fit", "drag", jumps.to_str().unwrap(), "--model", "eq4"],
        &["--model eq4 has no alpha"],
    );
    refused(
        &["fit", "inertial", jumps.to_str().unwrap(), "--model", "eq1"],
        &["--model eq1 has no b"],
    );
    let good = dir.path().join("good.csv");
    write_intrusion(&good);
    let unwritable = "/nonexistent-dir/out.toml";
    refused(
        &[
            "fit",
            "intrusion",
            good.to_str().unwrap(),
            "--out",
            unwritable,
        ],
        &["cannot write", unwritable],
    );
}
