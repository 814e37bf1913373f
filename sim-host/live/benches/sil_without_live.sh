#!/usr/bin/env bash
# The live path costs a sil jump nothing when --live is not given: `hil --bench` (the delayed
# stutter through the sil loop, 200 runs in one process, the median run's speed) with this
# build and with the build before the live view, side by side, alternating, 5 rounds; prints
# each round, the medians and their ratio.
#
# Usage: sim-host/live/benches/sil_without_live.sh [BASE_REV]
#   BASE_REV: the build to compare with (default: the commit before sim-host/live was added).
#   BASE_BIN=PATH uses an already built base binary instead.
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)"
cd "$root"
cargo build -q --profile fast -p sandjumper-cli
new="$root/target/fast/sandjumper"
if [ -z "${BASE_BIN:-}" ]; then
  added=$(git log --diff-filter=A --format=%H -- sim-host/live/Cargo.toml | tail -n 1)
  rev=${1:-$added^}
  base_dir="$root/target/bench-base"
  rm -rf "$base_dir" && git worktree prune
  git worktree add -q --detach "$base_dir" "$rev"
  (cd "$base_dir" && CARGO_TARGET_DIR="$root/target/bench-base-target" \
    cargo build -q --profile fast -p sandjumper-cli)
  BASE_BIN="$root/target/bench-base-target/fast/sandjumper"
fi
args=(hil --kind delayed --tau 0.1 --freq 10 --bench 200)
# The median run's real-time factor (three figures; its wall time is printed to 0.1 ms only).
median_of() { "$1" "${args[@]}" 2>&1 | sed -n 's/.*median [0-9.]* s (\([0-9.]*\)x real time).*/\1/p'; }
now=(); base=()
for round in 1 2 3 4 5; do
  a=$(median_of "$new"); b=$(median_of "$BASE_BIN")
  now+=("$a"); base+=("$b")
  printf 'round %d: this build %sx real time, base %sx\n' "$round" "$a" "$b"
done
mid() { printf '%s\n' "$@" | sort -g | sed -n 3p; }
m_now=$(mid "${now[@]}"); m_base=$(mid "${base[@]}")
printf 'median of medians: this build %sx, base %sx real time; base/this %.3f (1.00: no cost)\n' \
  "$m_now" "$m_base" "$(echo "$m_base / $m_now" | bc -l)"
