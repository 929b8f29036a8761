#!/usr/bin/env python3
"""How closely a person's own face follows MediaPipe's scores, on the geometric signals the
retarget tests read on an avatar (`crates/cli/tests/retarget.rs`): the lower lip's drop, each
side's lids, the mouth corners' height and the brows' height, each against the scores it is
judged by. What an avatar can reach when it moves exactly as the person does.

Reads the landmarks `faceanim track VIDEO --raw RAW.json` keeps (MediaPipe's 478, in the
picture's pixels with a relative depth), measures each signal in the face's own frame — across
from eye corner to eye corner, up from the chin towards the forehead, in eye-corner distances —
so that the head's turn and the camera's distance drop out, and prints each signal's
correlation with its scores.

Usage: scripts/footage-geometry.py RAW.json [RAW.json …] [--json OUT]
"""
import argparse
import json
import math
import sys

# Landmarks (MediaPipe's face mesh): eye corners, forehead, chin, lips, lids, brows.
RIGHT_EYE_OUTER, LEFT_EYE_OUTER, FOREHEAD, CHIN = 33, 263, 10, 152
UPPER_LIP, LOWER_LIP, MOUTH_RIGHT, MOUTH_LEFT = 0, 17, 61, 291
LEFT_LID_UP, LEFT_LID_DOWN, RIGHT_LID_UP, RIGHT_LID_DOWN = 386, 374, 159, 145
RIGHT_BROW, LEFT_BROW = 105, 334
INNER_UPPER_LIP, INNER_LOWER_LIP = 13, 14

# Each signal, the scores it is judged by (their mean), and how it is measured from the
# heights `h` (up is positive).
SIGNALS = [
    ("lower lip", ["jawOpen"], lambda h: h(UPPER_LIP) - h(LOWER_LIP)),
    ("left lids", ["eyeBlinkLeft"], lambda h: -(h(LEFT_LID_UP) - h(LEFT_LID_DOWN))),
    ("right lids", ["eyeBlinkRight"], lambda h: -(h(RIGHT_LID_UP) - h(RIGHT_LID_DOWN))),
    ("mouth corners", ["mouthSmileLeft", "mouthSmileRight"],
     lambda h: 0.5 * (h(MOUTH_RIGHT) + h(MOUTH_LEFT))),
    # The same corners over the lips' middle: a smile's own motion, without the jaw's.
    ("mouth corners over the lips", ["mouthSmileLeft", "mouthSmileRight"],
     lambda h: 0.5 * (h(MOUTH_RIGHT) + h(MOUTH_LEFT))
     - 0.5 * (h(INNER_UPPER_LIP) + h(INNER_LOWER_LIP))),
    ("brows", ["browInnerUp"], lambda h: 0.5 * (h(RIGHT_BROW) + h(LEFT_BROW))),
    ("brows lowered", ["browDownLeft", "browDownRight"],
     lambda h: -0.5 * (h(RIGHT_BROW) + h(LEFT_BROW))),
]

# A score that moves less than this over a video (its 95th percentile over its 5th) is not
# judged, as the tests leave out channels that do not move.
MOVES = 0.1


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def correlation(xs, ys):
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    sxx = sum((x - mx) ** 2 for x in xs)
    syy = sum((y - my) ** 2 for y in ys)
    return sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else float("nan")


def spread(values):
    s = sorted(values)
    return s[int(0.95 * (len(s) - 1))] - s[int(0.05 * (len(s) - 1))]


def heights(landmarks):
    """The face frame's height function: a landmark's height over the eyes' middle, along the
    face's up (chin to forehead, made square to the eye line), in eye-corner distances."""
    right, left = landmarks[RIGHT_EYE_OUTER], landmarks[LEFT_EYE_OUTER]
    across = sub(left, right)
    width = math.sqrt(dot(across, across))
    across = [x / width for x in across]
    up = sub(landmarks[FOREHEAD], landmarks[CHIN])
    up = sub(up, [x * dot(up, across) for x in across])
    norm = math.sqrt(dot(up, up))
    up = [x / norm for x in up]
    middle = [(a + b) / 2 for a, b in zip(right, left)]
    return lambda i: dot(sub(landmarks[i], middle), up) / width


def measure(path):
    raw = json.load(open(path))
    rows = []
    for frame in raw["frames"]:
        landmarks = frame.get("landmarks")
        if not landmarks or len(landmarks) < 468:
            continue
        h = heights(landmarks)
        scores = dict(frame["scores"])
        rows.append(([signal(h) for _, _, signal in SIGNALS],
                     [sum(scores[c] for c in channels) / len(channels)
                      for _, channels, _ in SIGNALS]))
    result = {"frames": len(rows), "signals": {}}
    for k, (what, channels, _) in enumerate(SIGNALS):
        ours = [r[0][k] for r in rows]
        theirs = [r[1][k] for r in rows]
        if len(rows) < 10 or spread(theirs) < MOVES:
            continue
        result["signals"][what] = {"follows": round(correlation(ours, theirs), 3),
                                   "scores": channels}
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("raw", nargs="+", help="`faceanim track … --raw` output")
    parser.add_argument("--json", help="write the figures here too")
    args = parser.parse_args()
    report = {}
    for path in args.raw:
        try:
            report[path] = measure(path)
        except (OSError, ValueError, KeyError) as e:
            sys.exit(f"{path}: {e}")
        print(f"{path} ({report[path]['frames']} frames with a face)")
        for what, s in report[path]["signals"].items():
            print(f"  {what:30s} follows {' + '.join(s['scores'])} at r {s['follows']:.3f}")
    if args.json:
        json.dump(report, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
