"""Records the reference runtime's (LiteRT's) outputs of MediaPipe's three face models, so that
faceanim-track's Rust inference can be tested against them without Python.

Run from the repository root (needs numpy and ai-edge-litert from PyPI):
    python3 tools/record_reference_outputs.py
It writes crates/track/tests/reference/: the exact input tensors (raw u8 RGB) and outputs.json.
Inputs are crops of ../shared/images/ict-face-*.png, read with a minimal PNG decoder below (no
imaging library needed).
"""
import json
import struct
import zipfile
import zlib
from pathlib import Path

import numpy as np
from ai_edge_litert.interpreter import Interpreter

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "crates/track/tests/reference"
SHARED = ROOT.parent / "shared"


def read_png(path):
    """8-bit RGB or RGBA, non-interlaced PNG to an (h, w, 3) uint8 array."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", chunk)
        elif kind == b"IDAT":
            idat += chunk
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert depth == 8 and colour in (2, 6) and interlace == 0, header
    channels = 3 if colour == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * channels
    out = np.zeros((height, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.int32)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = np.frombuffer(raw, dtype=np.uint8, count=stride, offset=y * (stride + 1) + 1).astype(np.int32)
        cur = np.zeros(stride, dtype=np.int32)
        for x in range(stride):
            left = cur[x - channels] if x >= channels else 0
            up = prev[x]
            up_left = prev[x - channels] if x >= channels else 0
            if kind == 0:
                p = 0
            elif kind == 1:
                p = left
            elif kind == 2:
                p = up
            elif kind == 3:
                p = (left + up) // 2
            else:
                pa, pb, pc = abs(up - up_left), abs(left - up_left), abs(left + up - 2 * up_left)
                p = left if pa <= pb and pa <= pc else (up if pb <= pc else up_left)
            cur[x] = (line[x] + p) & 0xFF
        out[y] = cur
        prev = cur
    return out.reshape(height, width, channels)[:, :, :3]


def resize_nearest(img, size):
    h, w, _ = img.shape
    ys = (np.arange(size) * h // size).astype(int)
    xs = (np.arange(size) * w // size).astype(int)
    return img[ys][:, xs]


def run(model_bytes, inputs):
    interpreter = Interpreter(model_content=model_bytes)
    interpreter.allocate_tensors()
    for detail, value in zip(interpreter.get_input_details(), inputs):
        interpreter.set_tensor(detail["index"], value.astype(np.float32))
    interpreter.invoke()
    # Five decimals: far below the tolerances the tests use (0.5 px, 0.02), and half the size.
    return [np.round(interpreter.get_tensor(d["index"]).astype(float).ravel(), 5).tolist() for d in interpreter.get_output_details()]


def main():
    bundle = zipfile.ZipFile(ROOT / "models/face_landmarker.task")
    models = {name: bundle.read(name) for name in ("face_detector.tflite", "face_landmarks_detector.tflite", "face_blendshapes.tflite")}
    OUT.mkdir(parents=True, exist_ok=True)
    results = {}
    for case in ("neutral", "jawopen", "smile"):
        image = read_png(SHARED / f"images/ict-face-{case}.png")
        h, w, _ = image.shape
        # The face fills the middle of the 384×384 render: a square crop around it.
        crop = image[int(0.14 * h):int(0.86 * h), int(0.14 * w):int(0.86 * w)]
        face = resize_nearest(crop, 256)
        whole = resize_nearest(image, 128)
        (OUT / f"{case}-landmarks-input.rgb").write_bytes(face.tobytes())
        (OUT / f"{case}-detector-input.rgb").write_bytes(whole.tobytes())
        landmarks, presence, _ = run(models["face_landmarks_detector.tflite"], [face[None] / 255.0])
        regressors, logits = run(models["face_detector.tflite"], [whole[None] / 127.5 - 1.0])
        points = np.array(landmarks).reshape(478, 3)[:146, :2]
        scores = run(models["face_blendshapes.tflite"], [points[None]])[0]
        results[case] = {
            "landmarks": landmarks,
            "presence_logit": presence[0],
            "detector_regressors": regressors,
            "detector_logits": logits,
            # The first 146 landmarks, not MediaPipe's subset: this checks the runtime, not expressions.
            "blendshape_points": np.round(points.ravel(), 5).tolist(),
            "blendshape_scores": scores,
        }
    (OUT / "outputs.json").write_text(json.dumps({"runtime": "ai-edge-litert 2.3.0", "cases": results}))
    print("wrote", OUT)


if __name__ == "__main__":
    main()
