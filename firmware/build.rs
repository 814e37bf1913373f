//! Selects the board's memory layout and linker scripts.
//!
//! - `board-f407` (default): cortex-m-rt's `link.x`, which includes the workspace root's
//!   `memory.x` (STM32F407: flash at 0x0800_0000; the linker runs from the workspace root and
//!   finds it there), plus defmt's `defmt.x`.
//! - `board-qemu`: `link-mps2-an386.x` (cortex-m-rt's script including `mps2-an386.x` instead
//!   of `memory.x`): QEMU mps2-an386, code RAM at 0x0000_0000, data RAM at 0x2000_0000.
//!
//! The scripts are passed here rather than in `.cargo/config.toml` because rustflags cannot
//! depend on cargo features.

use std::env;
use std::fs;
use std::path::{Path, PathBuf};

fn copy_to(out_dir: &Path, src: &Path, name: &str) {
    let text = fs::read(src).unwrap_or_else(|e| panic!("reading {}: {e}", src.display()));
    fs::write(out_dir.join(name), text)
        .unwrap_or_else(|e| panic!("writing {name} to OUT_DIR: {e}"));
    println!("cargo:rerun-if-changed={}", src.display());
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    // The F407's control tick rate (firmware/src/board/f407.rs reads it with option_env!).
    println!("cargo:rerun-if-env-changed=SANDJUMPER_TICK_HZ");
    // A fault built into a bring-up test image (firmware/src/inject_f407.rs).
    println!("cargo:rerun-if-env-changed=SANDJUMPER_INJECT");
    let manifest_dir =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    // Only firmware targets link with these scripts; a host build just prints a message.
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let f407 = env::var_os("CARGO_FEATURE_BOARD_F407").is_some();
    let qemu = env::var_os("CARGO_FEATURE_BOARD_QEMU").is_some();
    match (f407, qemu) {
        (true, false) => {
            // Also on the search path, for tools that look there (flip-link finds it either way).
            copy_to(&out_dir, &manifest_dir.join("../memory.x"), "memory.x");
            println!("cargo:rustc-link-arg-bins=-Tlink.x");
            println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
        }
        (false, true) => {
            copy_to(&out_dir, &manifest_dir.join("mps2-an386.x"), "mps2-an386.x");
            copy_to(
                &out_dir,
                &manifest_dir.join("link-mps2-an386.x"),
                "link-mps2-an386.x",
            );
            println!("cargo:rustc-link-arg-bins=-Tlink-mps2-an386.x");
        }
        (true, true) => panic!(
            "features board-f407 and board-qemu are exclusive: build the emulated board with \
             `--no-default-features --features board-qemu`"
        ),
        (false, false) => panic!("select a board: feature board-f407 (default) or board-qemu"),
    }
    println!("cargo:rustc-link-search={}", out_dir.display());
}
