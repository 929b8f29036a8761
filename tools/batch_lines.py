#!/usr/bin/env python3
"""Makes a batch of speech lines for `faceanim batch`: flite's voices saying made-up dialogue,
a manifest (JSON Lines) with one lipsync row per line, and a few rows broken on purpose.

Usage: batch_lines.py DIR --lines N [--broken K] [--seed S]

Writes DIR/audio/*.wav, DIR/text/*.txt (some rows read their words from a file) and
DIR/lines.jsonl; prints a JSON object: the rows, which are broken and how, and the voices.
The broken rows, in turn: speech that does not exist, bytes that are no sound, a WAV with no
samples, an option the command does not have, a transcript file that does not exist.
"""

import argparse
import json
import os
import random
import struct
import subprocess

VOICES = ["kal", "slt", "awb", "rms"]
SUBJECTS = ["The captain", "My brother", "Every merchant", "Old Bob", "The pilot", "Her mother",
            "A baker", "The mayor", "Pam", "The boatman", "Your cousin", "The blacksmith"]
VERBS = ["bought", "buried", "painted", "measured", "promised", "mapped", "borrowed", "broke",
         "moved", "polished", "found", "brought"]
OBJECTS = ["the blue barrel", "a map of the bay", "my father's boots", "the broken pump",
           "five maple beams", "a bottle of milk", "the big brass bell", "a pair of boots",
           "the smallest boat", "a box of plums", "the map", "our best lamp"]
ENDINGS = ["before the storm.", "by the mill.", "last Monday.", "in the morning.",
           "for the market.", "behind the bank.", "near the palace.", "at the pub.",
           "without a word.", "on the beach.", "by moonlight.", "for my mother."]
BROKEN = ["missing speech", "not sound", "no samples", "unknown option", "missing transcript"]


def empty_wav(path):
    """A WAV header with no samples (16 kHz mono, 16-bit)."""
    header = b"RIFF" + struct.pack("<I", 36) + b"WAVEfmt " + struct.pack(
        "<IHHIIHH", 16, 1, 1, 16000, 32000, 2, 16) + b"data" + struct.pack("<I", 0)
    with open(path, "wb") as file:
        file.write(header)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("dir")
    parser.add_argument("--lines", type=int, required=True)
    parser.add_argument("--broken", type=int, default=0)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    os.makedirs(os.path.join(args.dir, "audio"), exist_ok=True)
    os.makedirs(os.path.join(args.dir, "text"), exist_ok=True)
    # The broken rows, spread over the manifest.
    step = max(1, args.lines // max(1, args.broken))
    broken = {k * step + step // 2: BROKEN[k % len(BROKEN)] for k in range(args.broken)}
    rows, made = [], []
    for k in range(args.lines):
        key = f"line_{k:04d}"
        voice = VOICES[k % len(VOICES)]
        words = " ".join([rng.choice(SUBJECTS), rng.choice(VERBS), rng.choice(OBJECTS),
                          rng.choice(ENDINGS)])
        wav = f"audio/{key}.wav"
        row = {"id": key, "kind": "lipsync", "speech": wav, "outputs": [f"out/{key}.json"]}
        if k % 10 == 3:
            with open(os.path.join(args.dir, "text", f"{key}.txt"), "w") as file:
                file.write(words + "\n")
            row["transcript"] = f"text/{key}.txt"
        else:
            row["text"] = words
        how = broken.get(k)
        path = os.path.join(args.dir, wav)
        if how == "missing speech":
            row["speech"] = f"audio/{key}-missing.wav"
        elif how == "not sound":
            with open(path, "wb") as file:
                file.write(bytes(rng.randrange(256) for _ in range(4000)))
        elif how == "no samples":
            empty_wav(path)
        elif how == "missing transcript":
            row.pop("text", None)
            row["transcript"] = f"text/{key}-missing.txt"
        if how not in ("missing speech", "not sound", "no samples"):
            subprocess.run(["flite", "-voice", voice, "-t", words, "-o", path], check=True)
        if how == "unknown option":
            row["options"] = {"frames-per-second": 30}
        rows.append(row)
        made.append({"id": key, "index": k, "voice": voice, "words": words, "broken": how})
    with open(os.path.join(args.dir, "lines.jsonl"), "w") as file:
        for row in rows:
            file.write(json.dumps(row) + "\n")
    print(json.dumps({"rows": made, "broken": {str(k): v for k, v in sorted(broken.items())},
                      "voices": VOICES}))


if __name__ == "__main__":
    main()
