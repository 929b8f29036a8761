#!/usr/bin/env bash
# Live lip sync's latency as a user meets it: the release studio on the built-in head, Debian's
# chromium with a fake microphone playing a synthetic voice (flite's rms: the calibration
# passage, then three lines with pauses), the page's microphone calibrated, and the latency and
# the mouth's delay at the voice's onsets measured by the page (tools/voice-bench.mjs).
# Usage: scripts/bench-voice.sh [ONSETS]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked -p faceanim >&2
work=$(mktemp -d)
studio=""
trap '[ -n "$studio" ] && kill "$studio" 2>/dev/null; rm -rf "$work"' EXIT
# The passage as the studio shows it (crates/speech/src/listen.rs), then the lines.
sed -n '/^pub const PASSAGE/,/";$/p' crates/speech/src/listen.rs \
  | sed -e '1s/^[^"]*"//' -e 's/\\$//' -e '$s/";$//' | tr '\n' ' ' > "$work/passage.txt"
flite -voice rms -f "$work/passage.txt" -o "$work/0.wav"
k=1
for line in "We often go fishing with our father in the early morning." \
  "Please bring me my blue map before the bus leaves." \
  "She sells sea shells by the sea shore on Thursday."; do
  flite -voice rms -t "$line" -o "$work/$k.wav"
  k=$((k + 1))
done
ffmpeg -loglevel error -y -i "$work/0.wav" -i "$work/1.wav" -i "$work/2.wav" -i "$work/3.wav" \
  -filter_complex "[0:a]apad=pad_dur=1[a];[1:a]apad=pad_dur=0.6[b];[2:a]apad=pad_dur=0.6[c];[3:a]apad=pad_dur=0.6[d];[a][b][c][d]concat=n=4:v=0:a=1,aresample=16000" \
  "$work/microphone.wav"
target/release/faceanim studio --port 0 --project "$work/bench.faceanim.json" > "$work/studio.log" 2>&1 &
studio=$!
for _ in $(seq 100); do
  url=$(grep -o 'http://127.0.0.1:[0-9]*/' "$work/studio.log" || true)
  [ -n "$url" ] && break
  sleep 0.1
done
[ -n "$url" ] || { cat "$work/studio.log" >&2; exit 1; }
node tools/voice-bench.mjs "$url" "$work/microphone.wav" "${1:-6}"
