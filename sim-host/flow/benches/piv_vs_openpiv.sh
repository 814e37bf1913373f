#!/usr/bin/env bash
# PIV speed and accuracy against OpenPIV, side by side in one run.
#
# The same 1280 x 1024 pair of synthetic grain images (5 px grains, read noise 3 levels, a
# uniform shift of (2.3, 1.15) px; `sandjumper piv-synthetic`), the same passes (64 -> 32 ->
# 16 px windows, 50 % overlap, window deformation), each tool timed end to end from the PNG
# files (reading included; ours also writes every output file and figure), alternating, 5
# rounds; both may use both cores; CLAHE off for ours, as OpenPIV has none by default. Prints each
# round, the median times, their ratio, and each tool's RMS error against the known shift
# (interior vectors, a window away from the edges).
#
# Installs OpenPIV from PyPI into its own virtual environment (target/bench-venv); needs
# python3 with venv. Usage: sim-host/flow/benches/piv_vs_openpiv.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)"
cd "$root"
work="$root/target/bench-piv"
venv="$root/target/bench-venv"
rm -rf "$work" && mkdir -p "$work"
cargo build -q --release -p sandjumper-cli
bin="$root/target/release/sandjumper"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --upgrade pip
fi
"$venv/bin/pip" install -q "openpiv>=0.26" imageio numpy
"$bin" piv-synthetic --field shift --magnitude 2.3 --size 1280x1024 --noise 3 --frames 2 \
  --out "$work/pair" 2>/dev/null
cat > "$work/openpiv_run.py" <<'PY'
import sys, time, numpy as np, imageio.v3 as iio
from openpiv import windef
a_path, b_path = sys.argv[1], sys.argv[2]
t0 = time.perf_counter()
a = iio.imread(a_path).astype(np.float64)
b = iio.imread(b_path).astype(np.float64)
s = windef.PIVSettings()
s.windowsizes = (64, 32, 16)
s.overlap = (32, 16, 8)
s.num_iterations = 3
s.subpixel_method = "gaussian"
s.deformation_method = "symmetric"
s.interpolation_order = 3
s.sig2noise_method = "peak2peak"
s.validation_first_pass = True
s.median_threshold = 2
s.replace_vectors = True
x, y, u, v, flags = windef.simple_multipass(a, b, s)
t = time.perf_counter() - t0
# OpenPIV's transform_coordinates turns y up: its v is minus the image displacement.
dx, dy = 2.3, 1.15
h, w = a.shape
yi = h - 1 - y
inner = (x > 24) & (x < w - 24) & (yi > 24) & (yi < h - 24)
err = np.sqrt(np.mean((u[inner] - dx) ** 2 + (-v[inner] - dy) ** 2))
print(f"{t:.4f} {err:.4f} {u.size}")
PY
ours_err() {
  python3 - "$1" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1] + "/fields/0000.csv")))
xs = [float(r["x_px"]) for r in rows]
ys = [float(r["y_px"]) for r in rows]
w, h = max(xs) + 8, max(ys) + 8
sq, n = 0.0, 0
for r, x, y in zip(rows, xs, ys):
    if 24 < x < w - 24 and 24 < y < h - 24 and r["u_px"]:
        sq += (float(r["u_px"]) - 2.3) ** 2 + (float(r["v_px"]) - 1.15) ** 2
        n += 1
print(f"{math.sqrt(sq / n):.4f} {len(rows)}")
PY
}
a="$work/pair/frame_000000.png"; b="$work/pair/frame_000001.png"
ours=(); theirs=()
for round in 1 2 3 4 5; do
  t0=$(date +%s.%N)
  "$bin" piv "$work/pair" --clahe-tile 0 --out "$work/ours" >/dev/null 2>&1
  t1=$(date +%s.%N)
  rm -rf "$work/ours_keep" && mv "$work/ours" "$work/ours_keep"
  ours+=("$(echo "$t1 - $t0" | bc -l)")
  read -r t_opv err_opv n_opv < <("$venv/bin/python" "$work/openpiv_run.py" "$a" "$b" | tail -n 1)
  theirs+=("$t_opv")
  printf 'round %d: sandjumper %.3f s, OpenPIV %.3f s\n' "$round" "${ours[-1]}" "$t_opv"
done
read -r err_ours n_ours < <(ours_err "$work/ours_keep")
median() { printf '%s\n' "$@" | sort -g | sed -n 3p; }
m_ours=$(median "${ours[@]}"); m_theirs=$(median "${theirs[@]}")
printf 'median: sandjumper %.3f s (%s vectors, RMS error %s px), OpenPIV %.3f s (%s vectors, RMS error %s px)\n' \
  "$m_ours" "$n_ours" "$err_ours" "$m_theirs" "$n_opv" "$err_opv"
printf 'OpenPIV / sandjumper time ratio: %.2f (target >= 3)\n' "$(echo "$m_theirs / $m_ours" | bc -l)"
