#!/usr/bin/env bash
# Fails when a crate depends, directly or not, on what belongs to a layer above it. Three bands:
#   - the pure core (character, animation, sketch, default head, the retarget map) knows no HTTP server, async
#     runtime, video or neural network;
#   - the middle band (face tracking, media, capture, the take layer, the exporter, VMC, shape
#     generation) may run
#     MediaPipe's models with tract, but knows no HTTP server, async runtime or training library;
#   - speech (the recogniser's bindings and lip sync) knows neither the face models nor HTTP,
#     async runtimes or training: audio is its own domain.
# Keeps the core fast to build and usable anywhere, and the front ends thin.
set -euo pipefail
cd "$(dirname "$0")/.."

status=0
check() {
  local band=$1 forbidden=$2
  shift 2
  for crate in "$@"; do
    found=$(cargo tree --locked -p "$crate" -e normal --prefix none --format '{p}' | awk '{print $1}' | grep -E "$forbidden" | sort -u || true)
    if [ -n "$found" ]; then
      echo "check-layers: $crate ($band) must not depend on: $found" >&2
      status=1
    fi
  done
}
check "pure core" '^(tract-|axum|tokio|hyper|reqwest|burn|candle|ort|ffmpeg|rust-embed|tower)' \
  faceanim-rig faceanim-anim faceanim-sketch faceanim-head faceanim-retarget
check "middle band" '^(axum|tokio|hyper|reqwest|burn|candle|rust-embed|tower)' \
  faceanim-track faceanim-media faceanim-capture faceanim-take faceanim-export faceanim-live \
  faceanim-fit
check "speech" '^(tract-|axum|tokio|hyper|reqwest|burn|candle|ort|rust-embed|tower|faceanim-track|faceanim-capture)' \
  faceanim-sphinx-sys faceanim-speech
[ "$status" -eq 0 ] && echo "check-layers: the pure core, the middle band and speech depend on nothing above them"
exit "$status"
