#!/usr/bin/env bash
# `cargo run` runner for thumbv7em-none-eabihf (see .cargo/config.toml): picks the board from the
# ELF's entry address. STM32F407 images run from flash (0x0800_0000): flash and run them with
# probe-rs (defmt logs over RTT) when a debug probe is attached; with none (or no probe-rs), run
# them on the virtual STM32F407 board instead (sim-host/virtual-f407, its log decoded as
# probe-rs shows it, at real time until Ctrl-C), saying so on the first line. mps2-an386 images
# run from code RAM at 0x0000_0000: boot them in QEMU with firmware/qemu-run.sh.
#
# PROBE_RS names the probe-rs program (default: probe-rs on PATH); VIRTUAL_F407 the virtual
# board's program (default: sim-host/virtual-f407/target/release/virtual-f407, which
# sim-host/virtual-f407/build.sh builds).
set -euo pipefail
elf=$1
here=$(cd "$(dirname "$0")" && pwd)
# e_entry of an ELF32 file: 4 little-endian bytes at offset 24.
entry=$(od -An -tx4 -j24 -N4 "$elf" | tr -d ' ')
if [[ $((16#$entry)) -lt $((16#08000000)) ]]; then
  exec "$here/qemu-run.sh" "$@"
fi
probe_rs=${PROBE_RS:-probe-rs}
# `probe-rs list` numbers each attached probe: "[0]: STLink V2-1 ...".
if command -v "$probe_rs" >/dev/null 2>&1 && "$probe_rs" list 2>/dev/null | grep -q '^\[0\]'; then
  exec "$probe_rs" run --chip STM32F407VGTx "$@"
fi
if command -v "$probe_rs" >/dev/null 2>&1; then
  why="no debug probe attached"
else
  why="no $probe_rs to reach a debug probe with"
fi
board=${VIRTUAL_F407:-$here/../sim-host/virtual-f407/target/release/virtual-f407}
if [[ ! -x $board ]]; then
  echo "$why, and no virtual board at $board to run $elf on instead:" \
    "build it with sim-host/virtual-f407/build.sh (rustc 1.98.0, see sim-host/virtual-f407/README.md)" >&2
  exit 2
fi
echo "$why: running $elf on the virtual STM32F407 board (sim-host/virtual-f407), not on hardware; Ctrl-C stops it"
exec "$board" --elf "$elf" --run
