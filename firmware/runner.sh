#!/usr/bin/env bash
# `cargo run` runner for thumbv7em-none-eabihf (see .cargo/config.toml): picks the board from the
# ELF's entry address. STM32F407 images run from flash (0x0800_0000): flash and run them with
# probe-rs (defmt logs over RTT). mps2-an386 images run from code RAM at 0x0000_0000: boot them
# in QEMU with firmware/qemu-run.sh.
set -euo pipefail
elf=$1
# e_entry of an ELF32 file: 4 little-endian bytes at offset 24.
entry=$(od -An -tx4 -j24 -N4 "$elf" | tr -d ' ')
if [[ $((16#$entry)) -ge $((16#08000000)) ]]; then
  exec probe-rs run --chip STM32F407VGTx "$@"
else
  exec "$(dirname "$0")/qemu-run.sh" "$@"
fi
