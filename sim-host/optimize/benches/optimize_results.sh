#!/usr/bin/env bash
# The tables of docs/optimize.md's "What it finds", from runs of this version with the
# command's defaults (seed 1, --verify sil: the answer and the paper's best refined through
# the controller with the same budget before they are compared):
#   1. each ground at the paper's amplitude (--max-stroke 0.01875) with 2 and 4 moves, and at
#      the rig's stroke (0.025), unseeded;
#   2. the 25 mm search started from the 18.75 mm answer too (--start-from);
#   3. a stroke for an uncertain bed, --phi-range 0.57:0.62.
# Each row: the answer and the paper's best through sil, their ratio, the search's restarts
# and how many came within 1 % of the best, and where the answer stands against the paper's
# measured regime (the rules it relies on; its height without the re-intrusion overshoot).
# About 25 minutes on 2 cores. Folders go to DIR (default: a temporary folder, removed).
#
# Usage: sim-host/optimize/benches/optimize_results.sh [DIR [GROUND ...]]
#   GROUND: "eq4 0.57", "eq4 0.62", "hard 0.57" or "range" (the phi range; default: all four).
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)"
cd "$root"
cargo build -q --profile fast -p sandjumper-cli
bin="$root/target/fast/sandjumper"
grounds=("eq4 0.57" "eq4 0.62" "hard 0.57" range)
if [ $# -ge 1 ]; then
  out=$1
  mkdir -p "$out"
  shift
  [ $# -ge 1 ] && grounds=("$@")
else
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi
# One search into $out/NAME with ARGS...; prints its row.
row() {
  local name=$1
  shift
  rm -rf "${out:?}/$name" "$out/$name.checkpoint"
  local t0 t1
  t0=$(date +%s)
  "$bin" optimize --verify sil "$@" --out "$out/$name" --json >"$out/$name.json"
  t1=$(date +%s)
  python3 - "$out/$name.json" "$name" "$((t1 - t0))" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
mm = lambda v: f"{1e3 * v:.1f} mm" if s["objective_unit"] == "m" else f"{v:.4g} {s['objective_unit']}"
a, v = s["restart_agreement"], s["validity"]
off = next((r for r in v["rescored"] if r["alternative"] == "no overshoot"), None)
kept = f"{100 * off['answer_value_alternative'] / off['answer_value']:.0f} %" if off else "-"
b = s["over_beds"]
worst = (f" | worst {mm(b['answer_worst'])} (mean {mm(b['answer_mean'])}), the paper's "
         f"{mm(b['paper_worst'])} (mean {mm(b['paper_mean'])})") if b["beds"] > 1 else ""
print(f"| {sys.argv[2]} | **{mm(s['best_value'])}** | {mm(s['best_paper_value'])} "
      f"({s['paper_answer']['label']}) | {s['value_ratio']:.2f} | {a['within_1_percent']} of "
      f"{a['feasible_runs']} (spread {mm(a['spread'])}) | {len(v['relies_on'])} | {kept} | "
      f"{sys.argv[3]} s{worst} |")
PY
}
echo "| search | answer (sil) | the paper's best, refined (sil) | ratio | runs within 1 % | rules relied on | kept without the overshoot | time |"
echo "|---|---|---|---|---|---|---|---|"
for ground in "${grounds[@]}"; do
  if [ "$ground" = range ]; then
    row "range-0.57-0.62" --phi-range 0.57:0.62 |
      sed "s/| range-0.57-0.62 |/| eq4 phi 0.57:0.62 (5 beds), 25 mm, 4 moves: worst case |/"
    continue
  fi
  set -- $ground
  model=$1 phi=$2
  tag="$model phi $phi"
  [ "$model" = hard ] && tag="hard"
  row "$model-$phi-18.75-2moves" --model "$model" --phi "$phi" --max-stroke 0.01875 --moves 2 |
    sed "s/| $model-$phi-18.75-2moves |/| $tag, 18.75 mm, 2 moves |/"
  row "$model-$phi-18.75" --model "$model" --phi "$phi" --max-stroke 0.01875 |
    sed "s/| $model-$phi-18.75 |/| $tag, 18.75 mm, 4 moves |/"
  row "$model-$phi-25" --model "$model" --phi "$phi" |
    sed "s/| $model-$phi-25 |/| $tag, 25 mm, 4 moves |/"
  row "$model-$phi-25-seeded" --model "$model" --phi "$phi" --start-from "$out/$model-$phi-18.75" |
    sed "s/| $model-$phi-25-seeded |/| $tag, 25 mm, 4 moves, from the 18.75 mm answer |/"
done
