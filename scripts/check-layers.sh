#!/usr/bin/env bash
# Fails when a pure crate (character, animation, sketch, default head) depends, directly or not,
# on what belongs only to the crates at the edges: HTTP servers, async runtimes, video, neural
# networks. Keeps the core fast to build and usable anywhere.
set -euo pipefail
cd "$(dirname "$0")/.."

forbidden='^(tract-|axum|tokio|hyper|reqwest|burn|candle|ort|ffmpeg|rust-embed|tower)'
status=0
for crate in faceanim-rig faceanim-anim faceanim-sketch faceanim-head; do
  found=$(cargo tree --locked -p "$crate" -e normal --prefix none --format '{p}' | awk '{print $1}' | grep -E "$forbidden" | sort -u || true)
  if [ -n "$found" ]; then
    echo "check-layers: $crate must stay pure but depends on: $found" >&2
    status=1
  fi
done
[ "$status" -eq 0 ] && echo "check-layers: the pure crates depend on no edge crates"
exit "$status"
