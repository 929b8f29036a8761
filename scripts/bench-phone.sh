#!/usr/bin/env bash
# A phone tracker held for a minute, as a VTuber's session runs: the release studio on a
# character (the built-in head, or the one given) listening for Live Link Face, PyPI's
# pylivelinkface playing SECONDS of frames at 60 fps to it on loopback (tools/livelinkface_send.py),
# and every frame forwarded over VMC to python-osc standing in for the VTuber app
# (tools/vmc_peer.py). Prints what the studio counted (packets, frames, dropped kinds) and each
# frame's delay from datagram in to VMC out (median, 95th percentile), and how many bundles the
# app received.
# Usage: scripts/bench-phone.sh [CHARACTER] [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
character=${1:-}
seconds=${2:-60}
frames=$((seconds * 60))
cargo build --release --locked -p faceanim >&2
work=$(mktemp -d)
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$work"' EXIT
free_port() {
  python3 -c 'import socket; s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}
phone=$(free_port)
http=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
python3 tools/vmc_peer.py receive --count "$frames" --timeout $((seconds + 60)) --out "$work/app.json" > "$work/peer.out" &
pids+=($!)
for _ in $(seq 1 50); do grep -q PORT "$work/peer.out" 2>/dev/null && break; sleep 0.1; done
app=$(sed -n 's/^PORT //p' "$work/peer.out")
target/release/faceanim studio ${character:+"$character"} --port "$http" \
  --project "$work/bench.faceanim.json" --phone live-link-face --phone-port "$phone" \
  --phone-settings "$work/phone.json" --vmc-send "127.0.0.1:$app" --vmc-names arkit \
  > "$work/studio.log" 2>&1 &
pids+=($!)
for _ in $(seq 1 600); do curl -sf "http://127.0.0.1:$http/api/capture/vmc" > /dev/null && break; sleep 0.1; done
python3 tools/livelinkface_send.py --to "$phone" --frames "$frames" --fps 60 --out "$work/sent.json"
sleep 1
curl -sf "http://127.0.0.1:$http/api/capture/vmc" > "$work/view.json"
wait "${pids[0]}" || true
python3 - "$work/view.json" "$work/app.json" "$frames" <<'PY'
import json, sys
view = json.load(open(sys.argv[1]))
app = json.load(open(sys.argv[2]))
out = {k: view.get(k) for k in ["packets", "frames", "malformed", "foreign", "oversized", "forwarded"]}
out["sent"] = int(sys.argv[3])
out["app_received"] = len(app["datagrams"])
print(json.dumps(out))
PY
