#!/usr/bin/env bash
# Fails when a crate depends, directly or not, on what belongs to a layer above it. Bands, from
# the bottom:
#   - the pure core (character, animation, sketch, default head, the retarget map, the allocator
#     setting) knows no HTTP server, async runtime, video or neural network;
#   - the middle band (face tracking, media, rendering, capture, the take layer, the exporter,
#     VMC, shape generation, the file-system edge, the batch's bookkeeping) may run MediaPipe's
#     models with tract, but knows no HTTP server, async runtime or training library;
#   - speech (the recogniser's bindings and lip sync) knows neither the face models nor HTTP,
#     async runtimes or training: audio is its own domain;
#   - learning (the adapter and the retarget map's calibration) may train, but knows no HTTP
#     server or async runtime;
#   - the front ends (the studio's server, the command line) may use everything.
# No crate of a band depends on a faceanim crate of a band above it, and every crate of the
# workspace is in one band (a new crate must say where it belongs).
# Keeps the core fast to build and usable anywhere, and the front ends thin.
set -euo pipefail
cd "$(dirname "$0")/.."

core=(faceanim-rig faceanim-anim faceanim-sketch faceanim-head faceanim-retarget faceanim-malloc)
middle=(faceanim-track faceanim-media faceanim-render faceanim-capture faceanim-take
  faceanim-export faceanim-live faceanim-fit faceanim-files faceanim-batch)
speech=(faceanim-sphinx-sys faceanim-espeak-sys faceanim-speech)
learning=(faceanim-adapt)
front=(faceanim-studio faceanim)
# Test fixtures: used by tests only.
fixtures=(faceanim-testdata)

web='axum.*|tokio.*|hyper.*|reqwest|rust-embed.*|tower.*'
training='burn.*|candle.*'
status=0
alternation() { local IFS='|'; echo "$*"; }
check() {
  local band=$1 forbidden=$2
  shift 2
  for crate in "$@"; do
    local tree found
    tree=$(cargo tree --locked -p "$crate" -e normal --prefix none --format '{p}')
    found=$(awk '{print $1}' <<<"$tree" | grep -E "$forbidden" | sort -u || true)
    if [ -n "$found" ]; then
      echo "check-layers: $crate ($band) must not depend on:" $found >&2
      status=1
    fi
  done
}
above_middle=$(alternation "${speech[@]}" "${learning[@]}" "${front[@]}")
check "pure core" "^($web|$training|tract-.*|ort|ffmpeg.*|$(alternation "${middle[@]}" "${speech[@]}" "${learning[@]}" "${front[@]}"))\$" \
  "${core[@]}"
check "middle band" "^($web|$training|$above_middle)\$" "${middle[@]}"
check "speech" "^($web|$training|tract-.*|ort|faceanim-track|faceanim-capture|$(alternation "${learning[@]}" "${front[@]}"))\$" \
  "${speech[@]}"
check "learning" "^($web|$(alternation "${front[@]}"))\$" "${learning[@]}"

# Every workspace member is in a band.
banded=" ${core[*]} ${middle[*]} ${speech[*]} ${learning[*]} ${front[*]} ${fixtures[*]} "
metadata=$(cargo metadata --locked --no-deps --format-version 1)
members=$(python3 -c 'import json, sys; print("\n".join(p["name"] for p in json.load(sys.stdin)["packages"]))' <<<"$metadata")
for member in $members; do
  case "$member" in tract-*) continue ;; esac
  if [[ "$banded" != *" $member "* ]]; then
    echo "check-layers: $member is in no band: add it to scripts/check-layers.sh" >&2
    status=1
  fi
done
[ "$status" -eq 0 ] && echo "check-layers: every crate is in a band, and none depends on a band above it"
exit "$status"
