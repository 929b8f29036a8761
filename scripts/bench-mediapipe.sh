#!/usr/bin/env bash
# faceanim's capture side by side with MediaPipe's own runtime, on the same video in one run:
# frames per second of each (the whole loop: decoding, detection when the face is lost,
# landmarks, blendshapes), their ratio, and how far faceanim's ARKit scores are from
# MediaPipe's on the same frames.
#
# It makes a Python venv with PyPI mediapipe in target/mediapipe-venv (once), a 640×480 video of
# a face moving over a background (the astronaut photograph of ../shared/images, or VIDEO as
# the first argument), and runs `faceanim track` (release build) and tools/mediapipe_bench.py.
# Usage: scripts/bench-mediapipe.sh [VIDEO]
set -euo pipefail
cd "$(dirname "$0")/.."

venv=target/mediapipe-venv
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c 'import mediapipe' 2>/dev/null; then
  echo "bench: making $venv with PyPI mediapipe" >&2
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check mediapipe==0.10.21
fi

out=target/bench-mediapipe
mkdir -p "$out"
video="${1:-$out/face.mp4}"
if [ -z "${1:-}" ] && [ ! -f "$video" ]; then
  # Ten seconds at 30 fps: the photo, 400 px square, drifting over a grey background.
  ffmpeg -loglevel error -y -f lavfi -i color=c=gray:s=640x480:r=30:d=10 \
    -loop 1 -i ../shared/images/astronaut.png \
    -filter_complex "[1]scale=400:400[face];[0][face]overlay=x='120+40*sin(t)':y='40+20*sin(1.3*t)':shortest=1" \
    -pix_fmt yuv420p -c:v libx264 -crf 18 "$video"
fi

cargo build --release --locked -p faceanim >&2
faceanim=target/release/faceanim
"$faceanim" track "$video" --raw "$out/faceanim-raw.json" -o "$out/faceanim.json" --filter none \
  >"$out/faceanim-summary.json"
"$venv/bin/python" tools/mediapipe_bench.py "$video" models/face_landmarker.task \
  >"$out/mediapipe.json"

"$venv/bin/python" - "$out" <<'PY'
import json, sys
out = sys.argv[1]
ours = json.load(open(f"{out}/faceanim-summary.json"))
raw = json.load(open(f"{out}/faceanim-raw.json"))
theirs = json.load(open(f"{out}/mediapipe.json"))
differences = {}
compared = 0
for ours_frame, their_scores in zip(raw["frames"], theirs["scores"]):
    if not ours_frame["scores"] or their_scores is None:
        continue
    compared += 1
    for name, score in ours_frame["scores"]:
        if name == "_neutral" or name not in their_scores:
            continue
        d = abs(score - their_scores[name])
        worst = differences.get(name, (0.0, 0.0))
        differences[name] = (max(worst[0], d), worst[1] + d)
ranked = sorted(differences.items(), key=lambda kv: -kv[1][0])
report = {
    "frames": ours["frames"],
    "faceanim_fps": ours["frames_per_second"],
    "mediapipe_fps": theirs["frames_per_second"],
    "ratio": ours["frames_per_second"] / theirs["frames_per_second"],
    "faceanim_detector_runs": ours["detector_runs"],
    "frames_compared": compared,
    "largest_score_differences": [
        {"name": n, "max": round(m, 4), "mean": round(s / max(compared, 1), 4)} for n, (m, s) in ranked[:8]
    ],
}
print(json.dumps(report, indent=1))
PY
