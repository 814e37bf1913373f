//! Logs recorded from hardware-in-the-loop runs (`sandjumper hil --out`: the core's controller
//! against the force-driven plant), replayed in the kinematic simulation, give the jump height
//! of the original run within 2 % (issue 6). Also: `log check` accepts them, and bad logs exit
//! with status 2 and a message naming the line.

use std::path::Path;

mod common;
use common::sandjumper;

fn json_field(out: &std::process::Output, key: &str) -> f64 {
    assert!(
        out.status.success(),
        "command failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("`{key}` missing in {v}"))
}

/// (HIL, replay) pairs of jump height and final jump height.
fn hil_then_replay(dir: &Path, hil: &[&str], model: &str) -> [(f64, f64); 2] {
    let out_dir = dir.to_str().unwrap();
    let mut args = vec![
        "hil", "--link", "sil", "--model", model, "--out", out_dir, "--json",
    ];
    args.extend_from_slice(hil);
    let run = sandjumper(&args);
    let original = json_field(&run, "jump_height_m");
    let original_final = json_field(&run, "final_jump_height_m");
    let log = dir.join("acquisition.csv");
    let check = sandjumper(&["log", "check", log.to_str().unwrap()]);
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let replay = sandjumper(&["replay", log.to_str().unwrap(), "--model", model, "--json"]);
    [
        (original, json_field(&replay, "jump_height_m")),
        (original_final, json_field(&replay, "final_jump_height_m")),
    ]
}

#[test]
fn hil_logs_replay_to_the_original_jump_height_within_two_percent() {
    let tmp = tempfile::tempdir().unwrap();
    for (i, (hil, model)) in [
        (
            &["--kind", "single", "--freq", "10", "--phi", "0.57"][..],
            "eq4",
        ),
        (
            &["--kind", "stutter", "--freq", "12", "--phi", "0.57"][..],
            "hard",
        ),
        (
            &[
                "--kind", "delayed", "--freq", "12", "--tau", "0.3", "--phi", "0.62",
            ][..],
            "eq4",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        // The final jump height needs the push-off start, which replay takes from the
        // controller's PUSH_OFF flag in the log.
        let pairs = hil_then_replay(&tmp.path().join(i.to_string()), hil, model);
        for (what, (original, replayed)) in ["jump height", "final jump height"].iter().zip(pairs) {
            assert!(
                original > 5e-3,
                "{hil:?}: the HIL {what} must be above rest"
            );
            let error = (replayed - original).abs() / original;
            assert!(
                error < 0.02,
                "{hil:?} {model} {what}: replayed {replayed} m vs HIL {original} m ({:.2} %)",
                100.0 * error
            );
        }
    }
}

#[test]
fn bad_logs_exit_with_status_two_and_name_the_line() {
    let tmp = tempfile::tempdir().unwrap();
    let log = tmp.path().join("bad.csv");
    std::fs::write(
        &log,
        "# rate_hz: 1000\n# counts_per_m: 1e6\nt_s,encoder_counts\n0,0\n0.001,x\n",
    )
    .unwrap();
    for args in [
        vec!["replay", log.to_str().unwrap(), "--phi", "0.57"],
        vec!["log", "check", log.to_str().unwrap()],
    ] {
        let out = sandjumper(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("line 5: column `encoder_counts`: `x` is not a number"),
            "{err}"
        );
    }
    let missing = sandjumper(&["log", "check", "/nonexistent/log.csv"]);
    assert_eq!(missing.status.code(), Some(2));
    let no_phi = tmp.path().join("ok.csv");
    let mut text = String::from("# rate_hz: 10000\n# counts_per_m: 1e6\nt_s,encoder_counts\n");
    for k in 0..200 {
        text.push_str(&format!("{},{}\n", k as f64 * 1e-4, -18750));
    }
    std::fs::write(&no_phi, text).unwrap();
    let out = sandjumper(&["replay", no_phi.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("give the packing fraction with --phi"));
    let out = sandjumper(&["replay", no_phi.to_str().unwrap(), "--phi", "0.6", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A robot held still does not jump.
    assert!(json_field(&out, "jump_height_m") < 1e-4);
}
