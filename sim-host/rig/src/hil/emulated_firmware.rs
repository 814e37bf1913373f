//! The emulated-board firmware (QEMU `mps2-an386`) for processor-in-the-loop runs: what this
//! machine needs to build and boot it, and the build itself. One place for the PIL tests of
//! both packages, so they build the same ELF the same way (once, in a shared target dir).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use super::pil::PilConfig;

/// Target directory of the emulated build, relative to the workspace root. Separate from
/// `target/` (a running `cargo test` holds that lock, and the F407 build of the same name
/// lives there) and shared by every PIL test, by `.ci/run` and by `hil --link pil`'s default
/// `--firmware`, so the ELF is built once.
pub use crate::firmware_image::EMULATED_TARGET_DIR;

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
}

fn thumb_target_installed() -> bool {
    Command::new("rustc")
        .args([
            "--print",
            "target-libdir",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .output()
        .is_ok_and(|o| {
            o.status.success() && Path::new(String::from_utf8_lossy(&o.stdout).trim()).is_dir()
        })
}

/// What building and booting the emulated firmware needs and this machine lacks, each named
/// with how to install it. Empty when everything is there.
pub fn missing_prerequisites() -> Vec<&'static str> {
    [
        (
            "qemu-system-arm (apt-get install -y --no-install-recommends qemu-system-arm)",
            on_path("qemu-system-arm"),
        ),
        (
            "flip-link (cargo install flip-link --locked)",
            on_path("flip-link"),
        ),
        (
            "the thumbv7em-none-eabihf target (rustup target add thumbv7em-none-eabihf)",
            thumb_target_installed(),
        ),
    ]
    .into_iter()
    .filter_map(|(what, there)| (!there).then_some(what))
    .collect()
}

/// Build the emulated-board firmware (release, `--no-default-features --features board-qemu`)
/// into `workspace/EMULATED_TARGET_DIR` with the `cargo` running this process (or `cargo` from
/// `PATH`), and return the ELF. The error carries cargo's output.
pub fn build(workspace: &Path) -> Result<PathBuf, String> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(workspace)
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
            EMULATED_TARGET_DIR,
        ])
        .output()
        .map_err(|e| format!("running cargo to build the emulated firmware: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "building the emulated firmware failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(PilConfig::elf_in(&workspace.join(EMULATED_TARGET_DIR)))
}

/// The policy of every test that needs the emulated firmware: `Ok` when this machine has its
/// prerequisites; otherwise the message to skip the test with (`Err`, naming `what` and the
/// missing pieces; the test prints it), except under CI (`CI` set), where a missing
/// prerequisite fails the test (panics) instead of hiding it.
pub fn test_prerequisites(what: &str) -> Result<(), String> {
    let missing = missing_prerequisites();
    if missing.is_empty() {
        return Ok(());
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "CI must have: {}",
        missing.join(", ")
    );
    Err(format!("SKIPPED: {what} needs {}", missing.join(", ")))
}

/// [`build`] once per process (the first call builds, later calls return the same ELF or the
/// same error).
pub fn build_once(workspace: &Path) -> Result<&'static Path, String> {
    static ELF: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    ELF.get_or_init(|| build(workspace))
        .as_ref()
        .map(PathBuf::as_path)
        .map_err(Clone::clone)
}
