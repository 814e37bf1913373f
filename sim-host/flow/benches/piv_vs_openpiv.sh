#!/usr/bin/env bash
# PIV speed and accuracy against OpenPIV, side by side in one run.
#
# The same 1280 x 1024 pair of synthetic grain images (5 px grains, read noise 3 levels, a
# uniform shift of (2.3, 1.15) px; `sandjumper piv-synthetic`), the same passes (64 -> 32 ->
# 16 px windows, 50 % overlap, window deformation), each tool timed end to end from the PNG
# files (reading included; ours also writes every output file and figure), alternating, 5
# rounds; both may use both cores; ours with its defaults (local contrast on; OpenPIV has no
# enhancement by default). Prints each
# round, the median times, their ratio, and each tool's RMS error against the known shift
# (interior vectors, a window away from the edges).
#
# Then accuracy on a real image, side by side: OpenPIV's own test image (exp1_001_a.bmp,
# 511 x 369 px, taken at run time from the installed OpenPIV package: GPL-3.0, not shipped
# here) moved by exact sub-pixel shifts (`sandjumper piv-synthetic --image`, a Fourier
# shift), measured by ours with its defaults, by ours with PIVlab's CLAHE (64 px tiles), and
# by OpenPIV's multipass: bias and RMS of each component, per shift.
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
# The passes both OpenPIV runs use, as ours: 64 -> 32 -> 16 px, 50 % overlap, deformation.
cat > "$work/openpiv_settings.py" <<'PY'
from openpiv import windef
def settings():
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
    return s
PY
cat > "$work/openpiv_run.py" <<'PY'
import sys, time, numpy as np, imageio.v3 as iio
from openpiv import windef
from openpiv_settings import settings
a_path, b_path = sys.argv[1], sys.argv[2]
t0 = time.perf_counter()
a = iio.imread(a_path).astype(np.float64)
b = iio.imread(b_path).astype(np.float64)
s = settings()
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
  "$bin" piv "$work/pair" --out "$work/ours" >/dev/null 2>&1
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

# --- A real image moved by exact shifts: bias and RMS per component.
exp1="$("$venv/bin/python" -c 'import openpiv, os; print(os.path.join(os.path.dirname(openpiv.__file__), "data/test1/exp1_001_a.bmp"))')"
cat > "$work/openpiv_shift.py" <<'PY'
import sys, numpy as np, imageio.v3 as iio
from openpiv import windef
from openpiv_settings import settings
a_path, b_path, dx, dy = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
a = iio.imread(a_path).astype(np.float64)
b = iio.imread(b_path).astype(np.float64)
s = settings()
x, y, u, v, flags = windef.simple_multipass(a, b, s)
h, w = a.shape
yi = h - 1 - y
inner = (x > 32) & (x < w - 32) & (yi > 32) & (yi < h - 32)
eu, ev = u[inner] - dx, -v[inner] - dy
print(f"{eu.mean():+.4f} {ev.mean():+.4f} {np.sqrt((eu**2).mean()):.4f} {np.sqrt((ev**2).mean()):.4f}")
PY
ours_shift() {
  python3 - "$1" "$2" "$3" <<'PY'
import csv, math, sys
d, dx, dy = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
rows = list(csv.DictReader(open(d + "/fields/0000.csv")))
w = max(float(r["x_px"]) for r in rows) + 8
h = max(float(r["y_px"]) for r in rows) + 8
eu, ev = [], []
for r in rows:
    x, y = float(r["x_px"]), float(r["y_px"])
    if 32 < x < w - 32 and 32 < y < h - 32:
        eu.append(float(r["u_px"]) - dx if r["u_px"] else float("nan"))
        ev.append(float(r["v_px"]) - dy if r["v_px"] else float("nan"))
m = lambda e: sum(e) / len(e)
q = lambda e: math.sqrt(sum(a * a for a in e) / len(e))
print(f"{m(eu):+.4f} {m(ev):+.4f} {q(eu):.4f} {q(ev):.4f}")
PY
}
echo "real image (OpenPIV exp1_001_a, 511 x 369) moved by exact shifts: bias u, bias v, RMS u, RMS v (px)"
printf '%-12s %-34s %-34s %-34s\n' shift "sandjumper (defaults)" "sandjumper --clahe-tile 64" "OpenPIV multipass"
for shift in 5.25,3.75 0.5,0.25 2.3,-1.15 1.75,0.6 -3.4,1.3; do
  dx=${shift%,*}; dy=${shift#*,}
  rm -rf "$work/real"
  "$bin" piv-synthetic --field shift --image "$exp1" --shift="$shift" --out "$work/real" 2>/dev/null
  rm -rf "$work/real_ours" "$work/real_clahe"
  "$bin" piv "$work/real" --out "$work/real_ours" >/dev/null 2>&1
  "$bin" piv "$work/real" --local-contrast 0 --clahe-tile 64 --out "$work/real_clahe" >/dev/null 2>&1
  printf '%-12s %-34s %-34s %-34s\n' "$shift" "$(ours_shift "$work/real_ours" "$dx" "$dy")" \
    "$(ours_shift "$work/real_clahe" "$dx" "$dy")" \
    "$("$venv/bin/python" "$work/openpiv_shift.py" "$work/real/frame_000000.png" "$work/real/frame_000001.png" "$dx" "$dy" | tail -n 1)"
done
