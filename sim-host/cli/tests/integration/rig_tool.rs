//! `sandjumper rig` through the real binary against the simulated rig (`--link sil`; one
//! command through `--link pil` when QEMU is there): the contract. The files each command
//! writes, what `--json` prints, and the refusals that must come before anything moves (exit
//! 2, their messages, nothing written), each at its smallest configuration.
//!
//! What the commands measure (heights, the intrusion's curve, a replay matching its jump, the
//! plan's limits, calibration values, status contents, pil and the F407 binary against sil)
//! is tested through the library in `sim-host/rig/tests/integration/tool_sil.rs` and
//! `sim-host/rig/tests/integration/tool_links.rs`; `fit intrusion` recovering the rig's sand in
//! `sim-host/study/tests/integration/rig_fit.rs`.

use sandjumper_core::trajectory::JumpKind;
use sandjumper_output::Silent;
use sandjumper_rig::hil::emulated_firmware;
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::tool::jump::{self as rig_jump, JumpRequest};
use sandjumper_rig::tool::target::Target;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::Duration;

use crate::common;
use common::{ok, sandjumper, sandjumper_within, succeeded, workspace};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn assert_files(dir: &Path, files: &[&str]) {
    for f in files {
        assert!(dir.join(f).is_file(), "{f} written");
    }
}

/// The run in `dir` wrote `files` and its summary says it completed without a fault.
fn completed_run(dir: &Path, files: &[&str]) -> serde_json::Value {
    assert_files(dir, files);
    let sum = json(&dir.join("summary.json"));
    assert_eq!(sum["completed"], true);
    assert!(sum["faults"].as_array().unwrap().is_empty());
    sum
}

/// The acquisition log of a 10 Hz single jump through sil (run in this process, no camera),
/// written as `dir/jump.csv`: something for `rig replay` to replay.
fn jump_log(dir: &Path) -> PathBuf {
    let request = JumpRequest {
        camera_fps: 0,
        ..JumpRequest::new(Target::on(LinkArg::Sil), JumpKind::Single, 10.0)
    };
    let outcome = rig_jump::run(&request, &Silent).expect("the jump runs");
    let path = dir.join("jump.csv");
    outcome.log.write_file(&path).unwrap();
    path
}

/// `rig status --link sil --json`: the link and the controller's status (state, fault,
/// counters).
#[test]
fn status_through_sil_prints_the_controllers_status_as_json() {
    let o = sandjumper(&["rig", "status", "--link", "sil", "--json"]);
    succeeded(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["link"], "sil");
    assert!(v["status"]["state"].is_string(), "{v}");
    assert!(v["status"].get("fault").is_some(), "{v}");
    assert!(v["status"]["counters"]["samples_dropped"].is_u64(), "{v}");
}

/// `rig jump --out DIR` writes the log, parameters, summary, figure and the rendered camera
/// frames (one PNG per frame the summary counts); `log check` accepts the log. The camera at
/// 20 fps (the default 200 fps renders 160 frames, seconds of PNG encoding).
#[test]
fn jump_through_sil_writes_a_complete_log_that_log_check_accepts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("jump");
    ok(&[
        "rig",
        "jump",
        "--kind",
        "single",
        "--freq",
        "10",
        "--camera-fps",
        "20",
        "--out",
        s(&out),
        "--link",
        "sil",
    ]);
    let sum = completed_run(
        &out,
        &[
            "acquisition.csv",
            "params.toml",
            "summary.json",
            "jump.png",
            "jump.svg",
        ],
    );
    let pngs = std::fs::read_dir(out.join("frames"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "png")
        })
        .count() as u64;
    assert_eq!(pngs, sum["camera_frames"].as_u64().unwrap());
    ok(&["log", "check", s(&out.join("acquisition.csv"))]);
}

/// `rig intrude --out DIR --mcap` writes both curves, the log as CSV and MCAP, parameters,
/// summary and figure. A short program (40 mm/s, 50 ms holds; the defaults take 20 mm at
/// 10 mm/s with 0.5 s holds, measured in `sim-host/rig/tests/integration/tool_sil.rs`).
#[test]
fn intrusion_writes_its_curves_log_and_figure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("intrude");
    ok(&[
        "rig",
        "intrude",
        "--link",
        "sil",
        "--model",
        "eq1",
        "--speed",
        "0.04",
        "--hold",
        "0.05",
        "--out",
        s(&out),
        "--mcap",
    ]);
    completed_run(
        &out,
        &[
            "intrusion.csv",
            "reintrusion.csv",
            "acquisition.csv",
            "acquisition.mcap",
            "params.toml",
            "summary.json",
            "intrusion.png",
            "intrusion.svg",
        ],
    );
    let header = std::fs::read_to_string(out.join("intrusion.csv")).unwrap();
    assert_eq!(header.lines().next(), Some("depth_m,force_n"));
}

/// `rig replay LOG --out DIR` writes the new log, the uploaded table, parameters, summary and
/// figure, the summary naming the verified checksum.
#[test]
fn a_replay_writes_its_log_table_and_figure() {
    let dir = tempfile::tempdir().unwrap();
    let log = jump_log(dir.path());
    let out = dir.path().join("replay");
    ok(&["rig", "replay", s(&log), "--link", "sil", "--out", s(&out)]);
    let sum = completed_run(
        &out,
        &[
            "acquisition.csv",
            "table.csv",
            "params.toml",
            "summary.json",
            "replay.png",
        ],
    );
    assert!(sum["checksum"].as_str().unwrap().starts_with("0x"), "{sum}");
}

#[test]
fn replays_beyond_the_stroke_the_force_or_the_buffer_are_refused_before_anything_moves() {
    let dir = tempfile::tempdir().unwrap();
    let log = jump_log(dir.path());
    for (edit, value, reason) in [
        ("--scale", "1.5", "outside the stroke"),
        ("--time-stretch", "0.4", "of motor force"),
        ("--time-stretch", "6", "replay buffer holds 4096"),
    ] {
        let out = dir.path().join(format!("refused{edit}{value}"));
        let o = sandjumper(&[
            "rig",
            "replay",
            s(&log),
            "--link",
            "sil",
            edit,
            value,
            "--out",
            s(&out),
        ]);
        assert_eq!(o.status.code(), Some(2), "{edit} {value}: {}", stderr(&o));
        let msg = stderr(&o);
        assert!(
            msg.contains("refused before anything moved") && msg.contains(reason),
            "{msg}"
        );
        assert!(!out.exists(), "{edit} {value}: nothing was run or written");
    }
}

#[test]
fn bad_input_exits_2_with_a_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["rig", "status"], "--link"),
        (
            vec!["rig", "status", "--link", "sil", "--port", "/dev/ttyACM9"],
            "cannot be used with",
        ),
        (
            vec![
                "rig",
                "status",
                "--link",
                "f407",
                "--virtual-board",
                "/nonexistent/virtual-f407",
            ],
            "sim-host/virtual-f407/build.sh",
        ),
        (
            vec!["rig", "status", "--link", "sil", "--board-pace", "0.5"],
            "--board-pace paces the virtual board: it needs --link f407",
        ),
        (
            vec!["rig", "status", "--link", "f407", "--board-pace", "0"],
            "0.001..=1 times real time",
        ),
        (
            vec!["rig", "status", "--link", "f407", "--board-pace", "2"],
            "0.001..=1 times real time",
        ),
        (
            vec![
                "hil", "--link", "f407", "--kind", "single", "--freq", "5", "--bench", "2",
            ],
            "--bench is not available with --link f407",
        ),
        (
            vec!["rig", "status", "--port", "/nonexistent/tty"],
            "/nonexistent/tty",
        ),
        (
            vec![
                "rig",
                "replay",
                "/nonexistent.csv",
                "--link",
                "sil",
                "--out",
                s(&out),
            ],
            "/nonexistent.csv",
        ),
        (
            vec![
                "rig",
                "replay",
                "x.csv",
                "--link",
                "sil",
                "--clip",
                "3:1",
                "--out",
                s(&out),
            ],
            "START:END",
        ),
        (
            vec![
                "rig",
                "replay",
                "x.csv",
                "--link",
                "sil",
                "--scale",
                "-1",
                "--out",
                s(&out),
            ],
            "0 < X <= 10",
        ),
        (
            vec![
                "rig",
                "intrude",
                "--link",
                "sil",
                "--model",
                "hard",
                "--out",
                s(&out),
            ],
            "rigid floor",
        ),
        (
            vec![
                "rig",
                "intrude",
                "--link",
                "sil",
                "--depth",
                "0.02",
                "--withdraw",
                "0.005",
                "--reintrusion-depth",
                "0.01",
                "--out",
                s(&out),
            ],
            "reintrusion_depth_m",
        ),
        (
            vec![
                "rig",
                "intrude",
                "--link",
                "sil",
                "--speed",
                "0.5",
                "--out",
                s(&out),
            ],
            "speed",
        ),
        (
            vec![
                "rig",
                "jump",
                "--link",
                "sil",
                "--kind",
                "single",
                "--freq",
                "500",
                "--out",
                s(&out),
            ],
            "frequency",
        ),
    ];
    for (args, needle) in cases {
        let o = sandjumper(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{args:?}");
    }
    assert!(!out.exists());
}

#[test]
fn flash_is_a_no_op_for_sil_and_says_what_is_missing_for_a_board() {
    let o = sandjumper(&["rig", "flash", "--link", "sil"]);
    succeeded(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("nothing to flash"));
    let dir = tempfile::tempdir().unwrap();
    let elf = dir.path().join("fw.elf");
    std::fs::write(&elf, b"\x7fELF").unwrap();
    let o = sandjumper(&[
        "rig",
        "flash",
        "--port",
        "/dev/ttyACM0",
        "--firmware",
        s(&elf),
        "--probe-rs",
        s(&dir.path().join("no-probe-rs")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("probe-rs not found"), "{}", stderr(&o));
    let o = sandjumper(&[
        "rig",
        "flash",
        "--port",
        "/dev/ttyACM0",
        "--firmware",
        s(&dir.path().join("none.elf")),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("none.elf"), "{}", stderr(&o));
}

// --- PIL: the real firmware in QEMU ---------------------------------------------------------

/// Build the emulated board's firmware; `None` (skip, or fail in CI) when QEMU or the
/// firmware toolchain is missing or the firmware does not build here.
fn qemu_firmware() -> Option<PathBuf> {
    if emulated_firmware::test_prerequisites("rig through PIL")
        .map_err(|skip| eprintln!("{skip}"))
        .is_err()
    {
        return None;
    }
    match emulated_firmware::build_once(&workspace()) {
        Ok(elf) => Some(elf.to_path_buf()),
        Err(msg) => {
            assert!(std::env::var_os("CI").is_none(), "{msg}");
            eprintln!("SKIPPED: rig through PIL: {msg}");
            None
        }
    }
}

/// `rig status --link pil --firmware ELF --json`: the command reaches the firmware in QEMU and
/// prints its status (the jump through pil against sil: `sim-host/rig/tests/integration/tool_links.rs`).
#[test]
fn status_through_pil_prints_the_firmwares_status() {
    let Some(elf) = qemu_firmware() else { return };
    let o = sandjumper_within(
        &[
            "rig",
            "status",
            "--link",
            "pil",
            "--firmware",
            s(&elf),
            "--json",
        ],
        Duration::from_secs(120),
    );
    succeeded(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["link"], "pil");
    assert_eq!(v["status"]["state"], "Idle");
}

/// `rig calibrate-drive` sends the codes and saves them; `--drive-calibration FILE` sends the
/// saved codes with any later command (the status shows them); bad codes or a bad file are
/// refused with exit 2, naming what and where.
#[test]
fn the_drive_calibration_is_sent_saved_and_sent_again_from_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("drive.toml");
    let calibrate = |zero: &str, extra: &[&str]| {
        let mut args = vec![
            "rig",
            "calibrate-drive",
            "--link",
            "sil",
            "--zero-code",
            zero,
            "--codes-per-newton",
            "6.5",
        ];
        args.extend_from_slice(extra);
        sandjumper(&args)
    };
    let o = calibrate("2100", &["--save", s(&file)]);
    succeeded(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("0 N -> code 2100"));
    assert!(file.is_file(), "--save wrote the file");
    let o = sandjumper(&[
        "rig",
        "status",
        "--link",
        "sil",
        "--drive-calibration",
        s(&file),
        "--json",
    ]);
    succeeded(&o);
    let status: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(status["status"]["drive_calibration"]["zero_code"], 2100);
    let o = calibrate("3000", &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--zero-code"), "{}", stderr(&o));
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "zero_code = 2100\ngain = 6.5\n").unwrap();
    let o = sandjumper(&[
        "rig",
        "status",
        "--link",
        "sil",
        "--drive-calibration",
        s(&bad),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains(s(&bad)) && stderr(&o).contains("gain"),
        "{}",
        stderr(&o)
    );
    let o = sandjumper(&["rig", "acknowledge-reset", "--link", "sil"]);
    succeeded(&o);
}
