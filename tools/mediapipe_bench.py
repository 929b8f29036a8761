"""MediaPipe's own runtime on a video, for scripts/bench-mediapipe.sh: the Face Landmarker task
(the same face_landmarker.task faceanim embeds) in VIDEO mode — tracking from frame to frame, as
faceanim's capture does — reading the frames with OpenCV, timed from opening the video to the
last frame's scores (the clip's own set-up, decode, detect, landmarks, blendshapes; the model's
loading, once per process, is not counted, as faceanim's is not). Prints JSON: frames, seconds,
frames_per_second, and each frame's 52 scores (null where no face was found).
tools/record_footage_scores.py reads its footage through `video_scores` too.

Usage: python mediapipe_bench.py VIDEO MODEL.task
Needs PyPI mediapipe (which brings numpy and opencv); the bench script makes a venv for it.
"""
import json
import sys
import time

import cv2
import mediapipe as mp
from mediapipe.tasks.python import BaseOptions, vision


def video_scores(video, model):
    """Each frame's scores by name (None where no face was found), the video's frame rate, and
    the seconds from opening it to the last frame's scores."""
    options = vision.FaceLandmarkerOptions(
        base_options=BaseOptions(model_asset_path=str(model)),
        running_mode=vision.RunningMode.VIDEO,
        num_faces=1,
        output_face_blendshapes=True,
    )
    frames = []
    with vision.FaceLandmarker.create_from_options(options) as landmarker:
        started = time.perf_counter()
        capture = cv2.VideoCapture(str(video))
        fps = capture.get(cv2.CAP_PROP_FPS) or 30.0
        while True:
            ok, bgr = capture.read()
            if not ok:
                break
            rgb = cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
            image = mp.Image(image_format=mp.ImageFormat.SRGB, data=rgb)
            result = landmarker.detect_for_video(image, int(round(len(frames) * 1000 / fps)))
            if result.face_blendshapes:
                frames.append({c.category_name: c.score for c in result.face_blendshapes[0]})
            else:
                frames.append(None)
        seconds = time.perf_counter() - started
    return frames, fps, seconds


def main():
    frames, _, seconds = video_scores(sys.argv[1], sys.argv[2])
    print(json.dumps({
        "frames": len(frames),
        "seconds": seconds,
        "frames_per_second": len(frames) / max(seconds, 1e-9),
        "scores": frames,
    }))


if __name__ == "__main__":
    main()
