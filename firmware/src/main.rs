//! sandjumper firmware: thin glue between a board and `sandjumper-core`.
//!
//! - `board-f407` (default): the rig board, RTIC 2 (`app_f407`).
//! - `board-qemu`: QEMU mps2-an386, lockstep hardware-in-the-loop (`app_qemu`).
//!
//! Built only for `thumbv7em-none-eabihf`; a host build is a stub that says so, so that
//! `cargo test` / `cargo clippy` on the host never link firmware.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(all(target_os = "none", feature = "board-f407", feature = "board-qemu"))]
compile_error!(
    "board-f407 and board-qemu are exclusive: use --no-default-features --features board-qemu"
);

#[cfg(any(not(target_os = "none"), feature = "board-f407"))]
#[cfg_attr(not(target_os = "none"), allow(dead_code))]
mod drive;
#[cfg_attr(not(target_os = "none"), allow(dead_code))]
mod link;
#[cfg(any(not(target_os = "none"), feature = "board-f407"))]
#[cfg_attr(not(target_os = "none"), allow(dead_code))]
mod reset_flags;
#[cfg(any(not(target_os = "none"), feature = "board-qemu"))]
#[cfg_attr(not(target_os = "none"), allow(dead_code))]
mod session;

#[cfg(all(target_os = "none", feature = "board-f407"))]
mod app_f407;
#[cfg(target_os = "none")]
mod board;
#[cfg(all(target_os = "none", feature = "board-f407"))]
mod fault_f407;
#[cfg(all(target_os = "none", feature = "board-f407"))]
mod inject_f407;

#[cfg(all(target_os = "none", feature = "board-qemu"))]
mod app_qemu;
#[cfg(all(target_os = "none", feature = "board-qemu"))]
mod console;
#[cfg(all(target_os = "none", feature = "board-qemu"))]
mod selftest;
#[cfg(all(target_os = "none", feature = "board-qemu"))]
mod semihosting;
#[cfg(all(target_os = "none", feature = "board-qemu"))]
mod tick_cost;
#[cfg(all(target_os = "none", feature = "board-qemu"))]
mod transport;

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "sandjumper-firmware runs on the rig board or QEMU; build it with \
         `cargo build --release -p sandjumper-firmware --target thumbv7em-none-eabihf` \
         (the emulated board: add `--no-default-features --features board-qemu \
         --target-dir target/firmware`, its own directory, where `hil --link pil` looks)"
    );
}
