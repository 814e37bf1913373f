//! Logs recorded by `sandjumper hil --out` through the command line: `log check` accepts them
//! and `replay` reads them; bad logs exit with status 2 and a message naming the line. (That
//! replaying a HIL log gives the original jump height within 2 %, issue 6, is tested through
//! the libraries in `sim-host/study/tests/integration/hil_replay.rs`.)

use crate::common;
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

/// `hil --out DIR` (a 10 Hz single jump, camera off) writes acquisition.csv; `log check`
/// accepts it and `replay LOG --json` prints the jump heights of the replay.
#[test]
fn hil_logs_pass_log_check_and_replay() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("hil");
    let mut hil: Vec<&str> = "hil --link sil --kind single --freq 10 --camera-fps 0 --json"
        .split(' ')
        .collect();
    hil.extend(["--out", dir.to_str().unwrap()]);
    let run = sandjumper(&hil);
    json_field(&run, "jump_height_m");
    let log = dir.join("acquisition.csv");
    let check = sandjumper(&["log", "check", log.to_str().unwrap()]);
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let replay = sandjumper(&["replay", log.to_str().unwrap(), "--json"]);
    json_field(&replay, "jump_height_m");
    json_field(&replay, "final_jump_height_m");
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
    // With --phi the log replays (that a robot held still does not jump:
    // `sim-host/study/tests/integration/hil_replay.rs`).
    let out = sandjumper(&["replay", no_phi.to_str().unwrap(), "--phi", "0.6", "--json"]);
    json_field(&out, "jump_height_m");
}
