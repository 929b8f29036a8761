#!/usr/bin/env bash
# The whole `faceanim retarget` command as a user runs it (the template registered on the
# face, every channel fitted, then calibrated on the character's renders), timed with its peak
# memory, on rigs whose names say nothing: ICT-FaceKit identity 7 (about 25,000 vertices, 53
# shapes renamed shape_N by tools/rename_targets.py) and the test suite's Blender full-body
# avatar of another topology (VRoid-style keys carried onto a decimated face). Each is run
# three times; wall time and maximum resident memory from GNU time.
# Usage: scripts/bench-retarget.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked -p faceanim >&2
out=target/bench-retarget
mkdir -p "$out"
shared=${FACEANIM_SHARED:-../shared}
python3 tools/rename_targets.py "$shared/characters/ict-face-id7.glb" "$out/ict-id7.glb"
avatar=$(ls target/test-fixtures/blender-remeshed-avatar-*.glb 2>/dev/null | head -1 || true)
if [ -z "$avatar" ]; then
  cargo test --release --locked -p faceanim --test retarget a_full_body >&2
  avatar=$(ls target/test-fixtures/blender-remeshed-avatar-*.glb | head -1)
fi
cp "$avatar" "$out/avatar.glb"
for rig in ict-id7 avatar; do
  for run in 1 2 3; do
    /usr/bin/time -f "%e %M" -o "$out/$rig.time" target/release/faceanim retarget \
      "$out/$rig.glb" -o "$out/$rig.retarget.json" --remake --json >"$out/$rig.json" 2>/dev/null
    read -r seconds kib <"$out/$rig.time"
    echo "{\"rig\": \"$rig\", \"run\": $run, \"seconds\": $seconds, \"max_rss_mib\": $((kib / 1024))}"
  done
done
