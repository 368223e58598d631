#!/bin/bash
# What the web view costs the device (docs/tools.md "Web view"): a K110
# streaming GA at 2 kHz on a 2 Mbit/s line for FRAMES frames at SPEED
# (default 20000 frames = 10 device seconds, real time), recorded by
# `imu-emu client`; with the argument `web`, also `--web` and a poller
# asking /api/state every 100 ms, as the page does. Prints the wall time,
# the emulator's CPU time, device time held back and the poller's rate.
#
#   cargo build --release -p imu-emu-host
#   scripts/web-cost.sh; scripts/web-cost.sh web
set -euo pipefail
B="${CARGO_TARGET_DIR:-target}/release/imu-emu"
P="${PORT:-7350}"
W="${WEB_PORT:-7351}"
FRAMES="${FRAMES:-20000}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
args=(--tcp "127.0.0.1:$P" --power-on now --speed "${SPEED:-1}")
[ "${1:-}" = web ] && args+=(--web "127.0.0.1:$W")
"$B" "${args[@]}" >"$tmp/out" 2>"$tmp/err" &
emu=$!
sleep 0.4
C=("$B" client --tcp "127.0.0.1:$P")
"${C[@]}" set Data_Rate 2000 >/dev/null
"${C[@]}" set Baud_Rate 2000000 >/dev/null
"${C[@]}" commit-baud >/dev/null
poller=
if [ "${1:-}" = web ]; then
  WEB_PORT="$W" python3 - >"$tmp/poll" <<'PY' &
import json, os, time, urllib.request
port = os.environ["WEB_PORT"]
n, since, worst, t0 = 0, 0, 0.0, time.monotonic()
last = {}
try:
    while True:
        a = time.monotonic()
        r = urllib.request.urlopen("http://127.0.0.1:%s/api/state?dev=0&since=%d" % (port, since), timeout=2)
        last = json.loads(r.read())
        n += 1
        if last["points"]:
            since = last["points"][-1]["seq"]
        worst = max(worst, time.monotonic() - a)
        print("polls %d, %.2f a second, slowest %.0f ms, view_lost_bytes %s" % (
            n, n / (time.monotonic() - t0), worst * 1e3, last["view_lost_bytes"]), flush=True)
        time.sleep(max(0.0, 0.1 - (time.monotonic() - a)))
except Exception:
    pass
PY
  poller=$!
fi
start=$(date +%s.%N)
"${C[@]}" record --format GA --frames "$FRAMES" -o /dev/null
end=$(date +%s.%N)
echo "wall $(echo "$end - $start" | bc) s for $((FRAMES / 2000)) device s"
awk '{print "emulator cpu", ($14 + $15) / 100, "s"}' "/proc/$emu/stat"
[ -n "$poller" ] && kill "$poller" && tail -1 "$tmp/poll"
kill "$emu"
wait "$emu" 2>/dev/null || true
