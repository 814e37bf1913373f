#!/usr/bin/env bash
# Boots the emulated-board firmware (QEMU mps2-an386, Cortex-M4F) and returns its exit status.
#
#   firmware/qemu-run.sh ELF [FIRMWARE-ARGS...]
#
# FIRMWARE-ARGS reach the firmware as its semihosting command line:
#   selftest [ticks=N]      synthetic sensor feed, prints the tick-cost report, exits 0 if healthy
#   fifo IN_PATH OUT_PATH   lockstep hardware-in-the-loop over two host FIFOs (see README)
#   uart                    lockstep over the CMSDK UART0 (QEMU's -serial; set SANDJUMPER_QEMU_SERIAL)
# No arguments = selftest.
#
# Environment:
#   SANDJUMPER_QEMU_TIMEOUT  seconds before a hung firmware is killed (default 60; exit 124)
#   SANDJUMPER_QEMU_SERIAL   QEMU -serial backend for UART0 (default: none)
#
# -icount shift=6,align=off,sleep=off: virtual time advances 64 ns per instruction, whatever the
# host does, so the run is deterministic and SysTick (25 MHz) counts 1.6 per instruction; the
# firmware calibrates this ratio at boot and reports instructions.
set -euo pipefail
if [[ $# -lt 1 ]]; then
  echo "usage: $0 ELF [selftest [ticks=N] | fifo IN_PATH OUT_PATH | uart]" >&2
  exit 2
fi
elf=$1
shift
if ! command -v qemu-system-arm >/dev/null 2>&1; then
  echo "qemu-system-arm not found: apt-get install -y --no-install-recommends qemu-system-arm" >&2
  exit 127
fi
semihosting="enable=on,target=native"
for arg in "$@"; do
  if [[ $arg == *,* ]]; then
    echo "firmware argument '$arg' contains a comma, which QEMU's -semihosting-config cannot pass" >&2
    exit 2
  fi
  semihosting+=",arg=$arg"
done
exec timeout --kill-after=5 "${SANDJUMPER_QEMU_TIMEOUT:-60}" \
  qemu-system-arm -machine mps2-an386 -cpu cortex-m4 \
  -nographic -monitor none -serial "${SANDJUMPER_QEMU_SERIAL:-none}" \
  -semihosting-config "$semihosting" \
  -icount shift=6,align=off,sleep=off \
  -kernel "$elf"
