//! The emulated-board firmware (QEMU mps2-an386, Cortex-M4F) builds, boots, runs its self-test
//! (a synthetic sensor feed through the core's control tick, lockstep) and reports its exit
//! status through semihosting: 0 when healthy, non-zero on a fault, killed when hung.
//!
//! Skips with a message when `qemu-system-arm` is missing, unless `CI` is set (then it fails).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Own target directory: the outer `cargo test` holds the lock on `target/`'s host build.
const FIRMWARE_TARGET_DIR: &str = "target/firmware";

fn workspace() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn qemu_available() -> bool {
    let found = Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            std::env::var_os("CI").is_none(),
            "qemu-system-arm is required in CI (apt-get install -y --no-install-recommends qemu-system-arm)"
        );
        eprintln!("SKIPPED: qemu-system-arm not found; install it to boot the emulated firmware");
    }
    found
}

/// Builds the emulated-board firmware once per test run and returns the ELF.
fn firmware_elf() -> &'static Path {
    static ELF: OnceLock<PathBuf> = OnceLock::new();
    ELF.get_or_init(|| {
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let out = Command::new(cargo)
            .current_dir(workspace())
            .env_remove("RUSTFLAGS")
            .args([
                "build",
                "-p",
                "sandjumper-firmware",
                "--target",
                "thumbv7em-none-eabihf",
                "--release",
                "--no-default-features",
                "--features",
                "board-qemu",
                "--target-dir",
                FIRMWARE_TARGET_DIR,
            ])
            .output()
            .expect("running cargo build for the firmware");
        assert!(
            out.status.success(),
            "building the emulated firmware failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        workspace()
            .join(FIRMWARE_TARGET_DIR)
            .join("thumbv7em-none-eabihf/release/sandjumper-firmware")
    })
}

fn boot(args: &[&str], timeout_s: u32) -> (Output, Duration) {
    let start = Instant::now();
    let out = Command::new(workspace().join("firmware/qemu-run.sh"))
        .arg(firmware_elf())
        .args(args)
        .env("SANDJUMPER_QEMU_TIMEOUT", timeout_s.to_string())
        .output()
        .expect("running firmware/qemu-run.sh");
    (out, start.elapsed())
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The value of `key=` in the self-test's report line.
fn report_value(report: &str, key: &str) -> Option<u64> {
    report
        .split_whitespace()
        .find_map(|w| w.strip_prefix(key)?.strip_prefix('=')?.parse().ok())
}

#[test]
fn emulated_firmware_boots_runs_its_self_test_and_exits_zero() {
    if !qemu_available() {
        return;
    }
    let (out, _) = boot(&["selftest", "ticks=500"], 60);
    let log = text(&out);
    assert_eq!(
        out.status.code(),
        Some(0),
        "self-test should exit 0:\n{log}"
    );
    let report = log
        .lines()
        .find(|l| l.starts_with("selftest:"))
        .unwrap_or_else(|| panic!("no report line:\n{log}"));
    assert_eq!(report_value(report, "ticks"), Some(500), "{report}");
    // Every tick's cost was measured: a control tick cannot take zero instructions.
    let max = report_value(report, "max_tick_instructions").unwrap_or_else(|| panic!("{report}"));
    assert!(max > 0, "{report}");
}

#[test]
fn emulated_firmware_reports_an_injected_fault_in_its_exit_status() {
    if !qemu_available() {
        return;
    }
    // The synthetic encoder jumps by more than is physically possible in one tick: the core
    // latches an encoder fault, force goes to zero, and the firmware exits non-zero.
    let (out, _) = boot(&["selftest", "ticks=500", "inject=encoder-jump"], 60);
    let log = text(&out);
    let code = out.status.code();
    assert!(
        code.is_some_and(|c| c >= 16 && c != 124),
        "expected a fault exit status, got {code:?}:\n{log}"
    );
}

#[test]
fn a_hung_emulated_firmware_is_killed_within_seconds() {
    if !qemu_available() {
        return;
    }
    let (out, elapsed) = boot(&["hang"], 2);
    assert_eq!(
        out.status.code(),
        Some(124),
        "timeout(1) reports 124:\n{}",
        text(&out)
    );
    assert!(elapsed < Duration::from_secs(10), "took {elapsed:?}");
}
