#!/usr/bin/env python3
"""An independent Live Link Face sender for faceanim's tests, built on PyPI's pylivelinkface
(not on faceanim's own packet code): it plays a known face to 127.0.0.1:PORT the way Epic's
app does (one UDP datagram per frame, version 6, ARKit mode).

  livelinkface_send.py --to PORT --frames N --fps F --out FILE

pylivelinkface writes its version as a little-endian u32 and its device id without a length,
so its packets read as the app's only when the id is 36 characters long: the '$' it puts
first then stands for the length (36). A UUID's text is 36 characters.

Frame k sets JawOpen, EyeBlinkLeft and MouthSmileLeft and turns the head (radians, as the app
sends them); what was sent, with each frame's send time, is written as JSON.
"""
import argparse
import json
import math
import socket
import time
import uuid

from pylivelinkface import FaceBlendShape, PyLiveLinkFace


def values(k, n):
    u = k / max(1, n - 1)
    return {
        "JawOpen": round(0.5 - 0.5 * math.cos(6 * math.pi * u), 4),
        "EyeBlinkLeft": 1.0 if (k // 20) % 4 == 1 else 0.0,
        "MouthSmileLeft": round(u, 4),
        "HeadYaw": round(0.3 * math.sin(4 * math.pi * u), 4),
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--to", type=int, required=True)
    parser.add_argument("--frames", type=int, required=True)
    parser.add_argument("--fps", type=float, default=60.0)
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    face = PyLiveLinkFace(name="faceanim-test", uuid=str(uuid.uuid4()), fps=int(args.fps))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sent = []
    start = time.monotonic()
    for k in range(args.frames):
        # Paced by the clock, as the phone's camera is: no drift over a long run.
        wait = start + k / args.fps - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        frame = values(k, args.frames)
        for name, value in frame.items():
            face.set_blendshape(FaceBlendShape[name], value, no_filter=True)
        sock.sendto(face.encode(), ("127.0.0.1", args.to))
        sent.append({"time": time.monotonic() - start, "values": frame})
    with open(args.out, "w") as f:
        json.dump({"frames": sent, "seconds": time.monotonic() - start}, f)


if __name__ == "__main__":
    main()
