"""Records what MediaPipe's own runtime finds on a set of still images, so that faceanim's whole
per-frame pipeline (detector, face region, crop, landmarks, scores) can be checked against it on
the same pixels without Python: crates/track/tests/mediapipe_stills.rs.

Run from the repository root with PyPI mediapipe==0.10.21 (scripts/bench-mediapipe.sh makes
target/mediapipe-venv with it):
    target/mediapipe-venv/bin/python tools/record_mediapipe_stills.py SOURCE_DIR

SOURCE_DIR holds three.js renders of the ICT-FaceKit head (MIT) made by tools/heldout-stills.mjs
(the held-out stills the CLI's heldout test leaves in test-output/heldout/given). The script
copies some of them into crates/track/tests/reference/stills/, makes three harder ones from them
(the head rolled 20°; rolled the other way and moved so its crop runs off the frame's edge, where
MediaPipe repeats the edge pixels; half the size), and writes stills.json there: for each still
its size, MediaPipe's 478 landmarks (x, y in image pixels) and its 52 scores, from the Face
Landmarker task in IMAGE mode (the detector on every image, no smoothing) on the same
face_landmarker.task that faceanim embeds.
"""
import json
import shutil
import sys
from pathlib import Path

import cv2
import mediapipe as mp
import numpy as np
from mediapipe.tasks.python import BaseOptions, vision

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "crates/track/tests/reference/stills"
# Chosen among 60 held-out stills: the neutral and those on which faceanim's port differed
# most from MediaPipe before its crops followed MediaPipe's (pucker, brows, squint, upper lip).
COPIED = ["neutral.png", "0000.png", "0004.png", "0008.png", "0010.png", "0012.png", "0016.png"]


def rolled(image, degrees, shift=(0, 0)):
    """The image turned by `degrees` about the face (the picture's centre), then moved by
    `shift` pixels; what comes into view is the render's background colour."""
    h, w = image.shape[:2]
    matrix = cv2.getRotationMatrix2D((w / 2, h / 2), degrees, 1.0)
    matrix[:, 2] += shift
    background = tuple(int(v) for v in image[2, 2])
    return cv2.warpAffine(image, matrix, (w, h), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=background)


def main():
    source = Path(sys.argv[1])
    OUT.mkdir(parents=True, exist_ok=True)
    for name in COPIED:
        shutil.copyfile(source / name, OUT / name)
    rgb = lambda name: cv2.cvtColor(cv2.imread(str(source / name)), cv2.COLOR_BGR2RGB)
    made = {
        "0008-rolled.png": rolled(rgb("0008.png"), 20),
        "0010-edge.png": rolled(rgb("0010.png"), -25, shift=(250, 0)),
        "0004-small.png": cv2.resize(rgb("0004.png"), (320, 240), interpolation=cv2.INTER_AREA),
    }
    for name, image in made.items():
        cv2.imwrite(str(OUT / name), cv2.cvtColor(image, cv2.COLOR_RGB2BGR))

    options = vision.FaceLandmarkerOptions(
        base_options=BaseOptions(model_asset_path=str(ROOT / "models/face_landmarker.task")),
        running_mode=vision.RunningMode.IMAGE,
        num_faces=1,
        output_face_blendshapes=True,
    )
    record = {"mediapipe": mp.__version__, "stills": {}}
    with vision.FaceLandmarker.create_from_options(options) as landmarker:
        for name in COPIED + list(made):
            image = mp.Image.create_from_file(str(OUT / name))
            result = landmarker.detect(image)
            assert result.face_landmarks, f"{name}: MediaPipe found no face"
            w, h = image.width, image.height
            record["stills"][name] = {
                "width": w,
                "height": h,
                "landmarks": [[round(p.x * w, 3), round(p.y * h, 3)]
                              for p in result.face_landmarks[0]],
                "scores": {c.category_name: round(c.score, 5)
                           for c in result.face_blendshapes[0]},
            }
    (OUT / "stills.json").write_text(json.dumps(record, indent=0) + "\n")
    print(f"wrote {len(record['stills'])} stills to {OUT}")


if __name__ == "__main__":
    main()
