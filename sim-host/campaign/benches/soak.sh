#!/usr/bin/env bash
# The soak's speed (issue 54; the soak test itself, sim-host/cli/tests/integration/soak.rs,
# asserts no time): examples/campaign-soak.toml, 240 points through the simulated bed and
# controller at full speed, its live page open (--live), without and with 20 clients each
# polling /state.json ten times a second (one Python process, a kept-alive connection each),
# side by side, alternating, ROUNDS rounds (default 5).
# Prints each run's wall time, points per second and real-time factor, the medians and their
# ratio.
#
# Real-time factor: the rig time the campaign's jumps span (each point's acquisition record,
# 0.5-0.7 s; the bed's preparation is simulated, not timed) over the wall time.
#
# Usage: sim-host/campaign/benches/soak.sh [ROUNDS]
set -euo pipefail
root="$(cd "$(dirname "$0")/../../.." && pwd)"
cd "$root"
rounds=${1:-5}
cargo build -q --profile fast -p sandjumper-cli
bin="$root/target/fast/sandjumper"
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT

free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

# One campaign into $work/NAME with CLIENTS pollers; prints "wall_s rig_s states".
run() {
  local name=$1 clients=$2 port pid t0 t1
  port=$(free_port)
  rm -rf "${work:?}/$name"
  t0=$(date +%s.%N)
  "$bin" campaign run examples/campaign-soak.toml --link sil --out "$work/$name" \
    --live "127.0.0.1:$port" --linger 0 </dev/null >/dev/null 2>"$work/$name.err" &
  pid=$!
  local poller=""
  if [ "$clients" -gt 0 ]; then
    python3 - "$port" "$clients" "$pid" >"$work/$name.polls" <<'PY' &
# CLIENTS clients in one process (threads, a kept-alive connection each), each asking for
# /state.json ten times a second until the campaign's process ends; prints the states served.
import http.client, os, sys, threading, time
port, clients, pid = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
served = [0] * clients
def alive():
    try:
        os.kill(pid, 0)
        return True
    except OSError:
        return False
def poll(i):
    conn = None
    while alive():
        t = time.monotonic()
        try:
            conn = conn or http.client.HTTPConnection("127.0.0.1", port, timeout=5)
            conn.request("GET", "/state.json")
            r = conn.getresponse()
            r.read()
            served[i] += r.status == 200
        except OSError:
            conn = None
        time.sleep(max(0.0, 0.1 - (time.monotonic() - t)))
threads = [threading.Thread(target=poll, args=(i,)) for i in range(clients)]
for t in threads:
    t.start()
for t in threads:
    t.join()
print(sum(served))
PY
    poller=$!
  fi
  wait "$pid"
  t1=$(date +%s.%N)
  local states=0
  if [ -n "$poller" ]; then
    wait "$poller" || true
    states=$(cat "$work/$name.polls")
  fi
  local rig
  rig=$(python3 - "$work/$name" <<'PY'
import csv, pathlib, sys
total = 0.0
for log in sorted(pathlib.Path(sys.argv[1]).glob("points/*/acquisition.csv")):
    rows = [r for r in csv.reader(l for l in open(log) if not l.startswith("#")) if r and r[0].isdigit()]
    if rows:
        total += float(rows[-1][1]) - float(rows[0][1])
print(f"{total:.3f}")
PY
)
  echo "$(echo "$t1 - $t0" | bc -l) $rig $states"
}

without=(); with=()
for round in $(seq "$rounds"); do
  read -r w0 rig0 _ < <(run "r$round-none" 0)
  read -r w1 rig1 s1 < <(run "r$round-twenty" 20)
  without+=("$(echo "$rig0 / $w0" | bc -l)"); with+=("$(echo "$rig1 / $w1" | bc -l)")
  printf 'round %d: page only %.2f s (%.0f points/s, %.2fx real time); 20 clients %.2f s (%.0f points/s, %.2fx real time, %d states served)\n' \
    "$round" "$w0" "$(echo "240 / $w0" | bc -l)" "${without[-1]}" \
    "$w1" "$(echo "240 / $w1" | bc -l)" "${with[-1]}" "$s1"
done
mid() { printf '%s\n' "$@" | sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
range() { printf '%s\n' "$@" | sort -g | sed -n '1p;$p' | xargs printf '%.2f-%.2f'; }
m0=$(mid "${without[@]}"); m1=$(mid "${with[@]}")
printf 'median real-time factor: page only %.2fx (%s), 20 clients %.2fx (%s); with/without %.3f\n' \
  "$m0" "$(range "${without[@]}")" "$m1" "$(range "${with[@]}")" "$(echo "$m1 / $m0" | bc -l)"
