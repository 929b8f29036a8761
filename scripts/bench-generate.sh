#!/usr/bin/env bash
# The whole `faceanim generate-shapes` command as a user runs it, timed with its peak memory,
# on heads without blendshapes made by Blender: the test suite's bare full-body avatar (an
# ICT-FaceKit head, about 30,000 vertices in all, 24,591 in the face) and the same avatar
# subdivided once (about 120,000). Each is run three times; wall time and maximum resident
# memory from GNU time.
# Usage: scripts/bench-generate.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked -p faceanim >&2
out=target/bench-generate
mkdir -p "$out"
# The bare avatar, made (and cached) by the test support's Blender producer.
bare=$(ls target/test-fixtures/blender-bare-avatar-*.glb 2>/dev/null | head -1 || true)
if [ -z "$bare" ]; then
  cargo test --release --locked -p faceanim --test generate_shapes >&2
  bare=$(ls target/test-fixtures/blender-bare-avatar-*.glb | head -1)
fi
cp "$bare" "$out/avatar.glb"
[ -f "$out/avatar-subdivided.glb" ] || blender -b --factory-startup --python tools/blender_bare.py \
  -- "$out/avatar.glb" "$out/avatar-subdivided.glb" subdivide >/dev/null 2>&1
for head in avatar avatar-subdivided; do
  for run in 1 2 3; do
    /usr/bin/time -f "%e %M" -o "$out/$head.time" target/release/faceanim generate-shapes \
      "$out/$head.glb" -o "$out/$head.rigged.glb" --json >"$out/$head.json" 2>/dev/null
    read -r seconds kib <"$out/$head.time"
    vertices=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['vertices'])" "$out/$head.json")
    echo "{\"head\": \"$head\", \"vertices\": $vertices, \"run\": $run, \"seconds\": $seconds, \"max_rss_mib\": $((kib / 1024))}"
  done
done
