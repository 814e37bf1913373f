//! `--link f407` on a board slowed down (`--board-pace`), as a busy machine slows it: the host
//! counts its waits (the settle, the run's deadline, the answers, the board's exit) in the
//! board's virtual time, so the program runs as it does at full speed. Skipped (with a
//! message) without the virtual board or the F407 ELF, unless `CI` is set.

use std::path::Path;
use std::process::Output;
use std::time::Duration;

use crate::common;
use common::{sandjumper_within, virtual_board};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The summary of a short slow intrusion through `--link f407` (`pace`: `--board-pace`).
fn short_intrusion(out: &Path, pace: Option<&str>) -> serde_json::Value {
    let out_s = out.to_str().expect("a UTF-8 path");
    let mut args = vec![
        "rig",
        "intrude",
        "--link",
        "f407",
        "--model",
        "eq1",
        "--depth",
        "0.004",
        "--withdraw",
        "0.001",
        "--reintrusion-depth",
        "0.005",
        "--speed",
        "0.02",
        "--hold",
        "0.05",
        "--out",
        out_s,
    ];
    if let Some(p) = pace {
        args.extend(["--board-pace", p]);
    }
    let o = sandjumper_within(&args, Duration::from_secs(120));
    assert!(o.status.success(), "pace {pace:?}: {}", stderr(&o));
    let text = std::fs::read_to_string(out.join("summary.json")).expect("a summary");
    let sum: serde_json::Value = serde_json::from_str(&text).expect("summary JSON");
    assert_eq!(sum["completed"], true, "pace {pace:?}: {sum}");
    assert!(
        sum["faults"].as_array().is_some_and(|f| f.is_empty()),
        "pace {pace:?}: {sum}"
    );
    sum
}

/// A 0.7 s intrusion program (4 mm down at 20 mm/s, 50 ms holds, 1 mm back up, on to 5 mm,
/// back to the surface) after the 0.2 s settle, on a board at 0.05x real time: ~20 s of wall
/// time, past the run's 5.7 s deadline (the program's end + 5 s) that the host used to count
/// on the wall clock (measured: 23 s in all, force at 4 mm 6.14 N paced and unpaced).
#[test]
fn a_short_intrusion_on_a_board_at_a_twentieth_of_real_time_runs_as_at_full_speed() {
    if virtual_board().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("a temporary directory");
    let slow = short_intrusion(&dir.path().join("slow"), Some("0.05"));
    let wall_s = slow["wall_time_s"].as_f64().expect("the wall time");
    assert!(
        wall_s > 5.7,
        "the paced run took {wall_s} s of wall time: no longer than the old deadline"
    );
    let fast = short_intrusion(&dir.path().join("fast"), None);
    let force = |s: &serde_json::Value| s["force_at_depth_n"].as_f64().expect("a force");
    let (f_slow, f_fast) = (force(&slow), force(&fast));
    assert!(
        (f_slow - f_fast).abs() < 0.5,
        "force at 4 mm: paced {f_slow} N, unpaced {f_fast} N"
    );
}
