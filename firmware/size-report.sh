#!/usr/bin/env bash
# Flash and static-RAM use of a firmware ELF against the STM32F407 budgets (issue 4):
# flash < 128 KiB, static RAM < 96 KiB (the sample queue and every buffer are static).
#
#   firmware/size-report.sh ELF
#
# Uses llvm-size from the `llvm-tools` rustup component. Exits 1 if a budget is exceeded.
set -euo pipefail
elf=${1:?usage: $0 ELF}
sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
llvm_size="$sysroot/lib/rustlib/$host/bin/llvm-size"
if [[ ! -x $llvm_size ]]; then
  echo "llvm-size not found: rustup component add llvm-tools" >&2
  exit 2
fi
"$llvm_size" -A "$elf" | awk -v elf="$elf" '
  $1 == ".vector_table" || $1 == ".text" || $1 == ".rodata" { flash += $2 }
  $1 == ".data" { flash += $2; ram += $2 }
  $1 == ".bss" || $1 == ".uninit" { ram += $2 }
  { sizes[$1] = $2 }
  END {
    flash_budget = 128 * 1024; ram_budget = 96 * 1024
    printf "%s\n", elf
    printf "  flash      %7d B = %6.1f KiB  (budget %d KiB: .vector_table %d + .text %d + .rodata %d + .data %d)\n", \
      flash, flash / 1024, flash_budget / 1024, sizes[".vector_table"], sizes[".text"], sizes[".rodata"], sizes[".data"]
    printf "  static RAM %7d B = %6.1f KiB  (budget %d KiB: .data %d + .bss %d + .uninit %d; the stack takes the rest)\n", \
      ram, ram / 1024, ram_budget / 1024, sizes[".data"], sizes[".bss"], sizes[".uninit"]
    if (flash >= flash_budget || ram >= ram_budget) { print "  OVER BUDGET"; exit 1 }
  }'
