#!/usr/bin/env bash
# Time of `sandjumper optimize` with its defaults (paper sweep, CMA-ES search, candidates
# re-ranked through sil, the answer and the paper's best through pil when the emulated
# firmware and QEMU are there) at phi 0.57 and 0.62, on all cores and on one, side by side
# in alternating rounds. Prints each run's wall time and kinematic evaluations per second,
# the medians, the speed-up of all cores over one, and the target (at most 5 minutes).
#
# Usage: sim-host/optimize/benches/optimize_time.sh [ROUNDS]   (default 3)
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)"
cd "$root"
rounds=${1:-3}
cargo build -q --profile fast -p sandjumper-cli
bin="$root/target/fast/sandjumper"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
# One run: prints "wall_s evaluations_per_s".
one() {
  local phi=$1 threads=$2 out="$scratch/run"
  rm -rf "$out" "$out.checkpoint"
  local t0 t1
  t0=$(date +%s.%N)
  "$bin" optimize --phi "$phi" --threads "$threads" --out "$out" --json >"$scratch/summary.json"
  t1=$(date +%s.%N)
  python3 - "$scratch/summary.json" "$t0" "$t1" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"{float(sys.argv[3]) - float(sys.argv[2]):.2f} {s['evaluations_per_s']:.0f} {s['evaluations'] + s['paper_sweep_points']}")
PY
}
cores=$(nproc)
for phi in 0.57 0.62; do
  all=(); single=()
  for r in $(seq "$rounds"); do
    read -r wa ea na < <(one "$phi" "$cores")
    read -r w1 e1 n1 < <(one "$phi" 1)
    all+=("$wa"); single+=("$w1")
    printf 'phi %s round %d: %d threads %s s (%s evaluations/s, %s evaluations), 1 thread %s s (%s evaluations/s)\n' \
      "$phi" "$r" "$cores" "$wa" "$ea" "$na" "$w1" "$e1"
  done
  mid() { printf '%s\n' "$@" | sort -g | sed -n "$(( (${#@} + 1) / 2 ))p"; }
  ma=$(mid "${all[@]}"); m1=$(mid "${single[@]}")
  printf 'phi %s: median %s s on %d threads, %s s on 1: speed-up %.2fx; target 300 s: %s\n' \
    "$phi" "$ma" "$cores" "$m1" "$(echo "$m1 / $ma" | bc -l)" \
    "$(echo "$ma <= 300" | bc -l | sed 's/1/met/; s/0/NOT met/')"
done
