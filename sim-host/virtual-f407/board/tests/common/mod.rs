//! Shared by the tests on the F407 binary: where the ELF is, and the skip rule.
#![allow(dead_code)]

use std::path::PathBuf;

/// The F407 release ELF (`SANDJUMPER_F407_ELF`, or the main workspace's release build), or
/// `None` with a message (a panic under `CI`: there the ELF must have been built).
pub fn firmware_elf() -> Option<PathBuf> {
    let path = std::env::var_os("SANDJUMPER_F407_ELF")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../../target/thumbv7em-none-eabihf/release/sandjumper-firmware")
        });
    if path.is_file() {
        return Some(path);
    }
    let msg = format!(
        "skipped: no F407 firmware at {} (build it with `cargo build -p sandjumper-firmware --target thumbv7em-none-eabihf --release` in the main workspace)",
        path.display()
    );
    if std::env::var_os("CI").is_some() {
        panic!("{msg}; under CI the tests on the F407 binary must run");
    }
    eprintln!("{msg}");
    None
}
