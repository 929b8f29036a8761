#!/usr/bin/env python3
"""An independent VMC peer for faceanim's tests, built on PyPI's python-osc (not on faceanim's
own OSC code): it receives what a performer sends, or plays a known stream to a marionette.
Loopback only, bounded in count and time.

  vmc_peer.py receive --count N --timeout S --out FILE
      binds 127.0.0.1 on a free port, prints "PORT <n>", then keeps every datagram until N
      bundles with /VMC/Ext/Blend/Apply arrived or S seconds passed; writes the decoded
      messages (address, arguments with their OSC types) and arrival times as JSON.
  vmc_peer.py send --to PORT --frames N --fps F --out FILE [--garbage K] [--lose A:B]
                   [--names arkit|vrm]
      sends N frames of ARKit weights (JawOpen, EyeBlinkLeft, MouthSmileLeft, in ARKit's
      capitalised spelling; with --names vrm the same curves as the VRM 0.x presets A, Blink
      and Joy, as VSeeFace and VMagicMirror send without perfect sync), a head turn and the
      gaze (as the LeftEye and RightEye bones, as trackers send it) to 127.0.0.1:PORT at F
      frames per second, but
      frames A to B-1, which it keeps to itself as a Wi-Fi network loses datagrams; writes
      every frame (its time as /VMC/Ext/T says it, the lost ones marked) as JSON, then K
      garbage datagrams (random bytes, truncated bundles, huge datagrams, unknown addresses,
      wrong argument types).
"""
import argparse
import json
import math
import random
import socket
import sys
import time

from pythonosc import osc_bundle_builder, osc_message_builder
from pythonosc.osc_packet import OscPacket, ParseError

LOOPBACK = "127.0.0.1"


def typed(value):
    """An OSC argument as [type tag, value]."""
    if isinstance(value, bool):
        return ["T" if value else "F", value]
    if isinstance(value, int):
        return ["i", value]
    if isinstance(value, float):
        return ["f", value]
    if isinstance(value, str):
        return ["s", value]
    return ["?", repr(value)]


def receive(args):
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((LOOPBACK, 0))
    print(f"PORT {sock.getsockname()[1]}", flush=True)
    sock.settimeout(0.2)
    deadline = time.monotonic() + args.timeout
    datagrams = []
    applies = 0
    while applies < args.count and time.monotonic() < deadline:
        try:
            data, _ = sock.recvfrom(65536)
        except socket.timeout:
            continue
        arrived = time.monotonic()
        try:
            messages = [
                {"address": m.message.address, "args": [typed(p) for p in m.message.params]}
                for m in OscPacket(data).messages
            ]
        except ParseError as e:
            datagrams.append({"time": arrived, "error": str(e)})
            continue
        applies += sum(1 for m in messages if m["address"] == "/VMC/Ext/Blend/Apply")
        datagrams.append({"time": arrived, "messages": messages})
    with open(args.out, "w") as f:
        json.dump({"datagrams": datagrams}, f)


def message(address, *values):
    builder = osc_message_builder.OscMessageBuilder(address=address)
    for v in values:
        builder.add_arg(v, arg_type="f" if isinstance(v, float) else None)
    return builder.build()


def frame_values(k, n):
    """A known curve per name for frame k of n."""
    u = k / max(1, n - 1)
    return {
        "JawOpen": round(0.5 - 0.5 * math.cos(2 * math.pi * u), 4),
        "EyeBlinkLeft": 1.0 if (k // 10) % 3 == 1 else 0.0,
        "MouthSmileLeft": round(u, 4),
    }


# The VRM 0.x preset each of frame_values' curves is sent as under --names vrm.
VRM_PRESET = {"JawOpen": "A", "EyeBlinkLeft": "Blink", "MouthSmileLeft": "Joy"}


def head_quaternion(yaw_degrees, pitch_degrees=0.0):
    """A head (or an eye) turned by `yaw_degrees` (to the subject's own left when positive),
    then tipped by `pitch_degrees` (up when positive), as VMC sends it: Unity's left-handed
    frame, the mirror of glTF's X axis, so the turn about Y flips sign; Unity's X points to the
    subject's right, so tipping up turns about X the negative way."""
    yaw = math.radians(yaw_degrees) / 2
    pitch = math.radians(pitch_degrees) / 2
    # (0, -sin yaw, 0, cos yaw) * (-sin pitch, 0, 0, cos pitch), as x, y, z, w
    sy, cy, sp, cp = math.sin(yaw), math.cos(yaw), math.sin(pitch), math.cos(pitch)
    return [-cy * sp, -sy * cp, -sy * sp, cy * cp]


def gaze(k, n):
    """Both eyes' yaw and pitch in degrees at frame k of n: two sweeps left and right, one up
    and down."""
    u = k / max(1, n - 1)
    return [round(20.0 * math.sin(4 * math.pi * u), 3), round(10.0 * math.cos(2 * math.pi * u), 3)]


def send(args):
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    destination = (LOOPBACK, args.to)
    sent = []
    start = time.monotonic()
    for k in range(args.frames):
        due = start + k / args.fps
        wait = due - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        values = frame_values(k, args.frames)
        if args.names == "vrm":
            values = {VRM_PRESET[name]: value for name, value in values.items()}
        yaw = 30.0 * math.sin(2 * math.pi * k / max(1, args.frames))
        eyes = gaze(k, args.frames)
        now = time.monotonic() - start
        if args.lose[0] <= k < args.lose[1]:
            sent.append({"time": now, "values": values, "yaw": yaw, "eyes": eyes, "lost": True})
            continue
        bundle = osc_bundle_builder.OscBundleBuilder(osc_bundle_builder.IMMEDIATELY)
        bundle.add_content(message("/VMC/Ext/OK", 1))
        bundle.add_content(message("/VMC/Ext/T", float(now)))
        bundle.add_content(message("/VMC/Ext/Bone/Pos", "Head", 0.0, 0.0, 0.0, *head_quaternion(yaw)))
        for bone in ("LeftEye", "RightEye"):
            bundle.add_content(message("/VMC/Ext/Bone/Pos", bone, 0.0, 0.0, 0.0, *head_quaternion(*eyes)))
        for name, value in values.items():
            bundle.add_content(message("/VMC/Ext/Blend/Val", name, float(value)))
        bundle.add_content(message("/VMC/Ext/Blend/Apply"))
        sock.sendto(bundle.build().dgram, destination)
        sent.append({"time": now, "values": values, "yaw": yaw, "eyes": eyes})
    rng = random.Random(7)
    valid = message("/VMC/Ext/Blend/Val", "JawOpen", 0.5).dgram
    kinds = [
        lambda: bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 200))),
        lambda: valid[: rng.randint(1, len(valid) - 1)],
        lambda: b"#bundle\0" + bytes(rng.getrandbits(8) for _ in range(40)),
        lambda: bytes(40000),
        lambda: message("/not/vmc/at/all", 1.0).dgram,
        lambda: message("/VMC/Ext/Blend/Val", 3, "JawOpen").dgram,
        lambda: message("/VMC/Ext/Bone/Pos", "Head", 1.0).dgram,
    ]
    for g in range(args.garbage):
        sock.sendto(kinds[g % len(kinds)](), destination)
        # A flood, but one the receiver's socket buffer holds: what is counted is what arrived.
        time.sleep(0.001)
    with open(args.out, "w") as f:
        json.dump({"frames": sent}, f)


def frames_range(text):
    """A:B as the pair (A, B) of frame numbers."""
    try:
        first, end = (int(part) for part in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not A:B (two frame numbers)")
    return first, end


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    r = commands.add_parser("receive")
    r.add_argument("--count", type=int, required=True)
    r.add_argument("--timeout", type=float, required=True)
    r.add_argument("--out", required=True)
    s = commands.add_parser("send")
    s.add_argument("--to", type=int, required=True)
    s.add_argument("--frames", type=int, required=True)
    s.add_argument("--fps", type=float, required=True)
    s.add_argument("--out", required=True)
    s.add_argument("--garbage", type=int, default=0)
    s.add_argument("--lose", type=frames_range, default=(0, 0), metavar="A:B")
    s.add_argument("--names", choices=("arkit", "vrm"), default="arkit")
    args = parser.parse_args()
    # Bounded in count and time, whatever the caller asks.
    if args.command == "receive" and not (0 < args.count <= 100000 and 0 < args.timeout <= 120):
        parser.error("--count must be 1 to 100000 and --timeout 0 to 120 seconds")
    if args.command == "send" and not (0 <= args.frames <= 100000 and 0 < args.fps <= 240 and 0 <= args.garbage <= 100000):
        parser.error("--frames must be 0 to 100000, --fps 0 to 240, --garbage 0 to 100000")
    {"receive": receive, "send": send}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
