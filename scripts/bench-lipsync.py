#!/usr/bin/env python3
"""Lip sync as animators judge it, on synthetic voices whose every phone's time the synthesiser
itself reports: `faceanim lipsync` run as a user runs it (the whole command, timed), on a rig
whose 15 shapes are named as Ready Player Me's visemes (`viseme_*`: the built-in head's first
15 targets renamed), at 100 frames a second. Per voice and line, with the transcript and from
the audio alone:

- agreement: per 10 ms of speech, is the class of the phone's viseme (closed lips, lip to
  teeth, open, spread, round, tongue and teeth) the class of the rig's dominant viseme
  somewhere within ±40 ms;
- P/B/M: for every bilabial, do the lips close (viseme_PP ≥ 0.5) within its time ±40 ms;
- closures elsewhere: of the closures the rig makes (runs of frames with viseme_PP ≥ 0.5), how
  many lie more than 40 ms from every bilabial (the lips shut on a D, an N, a vowel). P/B/M
  counts closures that land; this counts those that should not have been made, which P/B/M
  and agreement (a few 10 ms frames each) barely see;
- silence: in every pause of at least 0.3 s (its middle, 0.1 s in from each end), the open
  shapes' largest weight (all but viseme_sil and viseme_PP);
- the command's wall-clock time over the sound's length.

Voices: flite's (kal, slt, rms, awb; `-psdur`), festival's (English diphone and HTS voices, and
Italian, Finnish, Czech and Catalan with `festival-it:`, `festival-fi:`, `festival-cs:`,
`festival-ca:`, as `festival-fi:voice_suo_fi_lj_diphone`; `utt.save.segs`),
eSpeak NG's (through its library with ctypes, phoneme events: a voice variant and rate other
than the ones faceanim aligns with). Languages other than English through eSpeak NG with
`--language` (eighteen: `--voices espeak:es,espeak:hi,…`).

A long reading: `--repeat 10` says each voice's lines as one recording, ten times over (flite's
slt: about four minutes; a woman's voice drifted there before the recogniser's frames were
whole samples, and English lines over 30 s are aligned a few sentences at a time).

Usage: scripts/bench-lipsync.py [--faceanim PATH] [--voices a,b] [--json OUT] [--lines N]
       [--repeat N] [--modes text,audio] [--recognise words|phones] [--ffmpeg-first] [--breakdown]
"""
import argparse
import collections
import ctypes
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import unicodedata

HARVARD = [
    "The birch canoe slid on the smooth planks.",
    "Glue the sheet to the dark blue background.",
    "It's easy to tell the depth of a well.",
    "These days a chicken leg is a rare dish.",
    "Rice is often served in round bowls.",
    "The juice of lemons makes fine punch.",
    "Mama made my bed before breakfast.",
    "Bob brought a big purple map to the bumpy boat.",
]

# Lines in other languages (their own words), spoken by eSpeak NG.
FOREIGN = {
    "es": ["Mi mamá me mima mucho.", "El perro de Pablo bebe agua en la playa."],
    "de": ["Guten Morgen, wie geht es dir?", "Meine Mutter mag warme Milch am Abend."],
    "fr": ["Bonjour, je m'appelle Paul.", "Ma mère prépare une bonne soupe pour le dîner."],
    "ja": ["こんにちは、ありがとうございます。", "まいにち、ももをたべます。"],
    "ko": ["안녕하세요, 만나서 반갑습니다.", "엄마는 매일 밥을 먹어요."],
    "it": ["Buongiorno, come stai?", "Mamma mia, il mare è bellissimo."],
    "pt": ["Bom dia, meu amigo.", "A minha mãe bebe muito café."],
    "ru": ["Мама мыла раму.", "Папа купил большую белую машину."],
    "pl": ["Mama ma małego psa.", "Proszę podać mi ten biały papier."],
    "tr": ["Bugün hava çok güzel.", "Babam bana mavi bir balon aldı."],
    "hi": ["मेरा नाम राम है।", "माँ बाज़ार से आम लाई।"],
    "ar": ["مرحبا كيف حالك؟", "أمي تحب الماء البارد."],
    "el": ["Καλημέρα, τι κάνεις;", "Η μαμά μου μαγειρεύει μπάμιες."],
    "vi": ["Xin chào, bạn khỏe không?", "Mẹ mua bánh mì buổi sáng."],
    "sw": ["Habari za asubuhi.", "Mama anapika mboga na mkate."],
    "nl": ["Goedemorgen, hoe gaat het?", "Mijn moeder maakt brood met boter."],
    "fi": ["Hyvää huomenta.", "Mummo paistaa pullaa ja piirakkaa."],
    # Mandarin in characters, told `zh` as users name it; spoken by eSpeak NG's pinyin voice
    # (its `zh` voice reads characters as numbered pinyin in English).
    "zh": ["妈妈每天买面包。", "你好，谢谢你的帮助。"],
}

# The voice that speaks a language's lines, where it is not the language's own.
SPEAKER = {"zh": "cmn-latn-pinyin"}

# Lines for Festival's voices in other languages (`festival-it:`, `festival-fi:`, `festival-cs:`,
# `festival-ca:`; Debian's festvox-italp16k and -itapc16k, festvox-suopuhe-lj and -mv,
# festvox-czech-krb, -ph and -dita, festvox-ca-ona-hts), with held (geminate) stops in Italian
# and Finnish.
FESTIVAL_LINES = {
    "it": FOREIGN["it"] + [
        "Il babbo porta il pane buono a casa.",
        "Paolo beve molto latte ogni mattina.",
        "Bianca mangia una mela matura nel prato.",
    ],
    "fi": FOREIGN["fi"] + [
        "Pekka meni metsään marjoja poimimaan.",
        "Tämä on minun pieni punainen talo.",
    ],
    "cs": [
        "Máma mele maso.",
        "Babička peče buchty a pije mléko.",
        "Pepa má modrou bundu a bílé boty.",
        "Dobré ráno, jak se máš?",
    ],
    "ca": [
        "La mare menja pa amb tomàquet.",
        "El meu pare porta un barret blau.",
        "Bon dia, com estàs?",
        "Mireia beu aigua cada matí a la platja.",
    ],
}
# How Festival reads a language's text (its scripts are bytes).
FESTIVAL_ENCODING = {"cs": "iso-8859-2"}

VISEMES = ["sil", "PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR", "aa", "E", "ih", "oh", "ou"]
CLASS = {
    "PP": "closed", "FF": "lip-teeth", "aa": "open", "E": "spread", "ih": "spread",
    "oh": "round", "ou": "round", "TH": "tongue", "DD": "tongue", "nn": "tongue",
    "SS": "tongue", "CH": "tongue", "kk": "tongue", "RR": "tongue", "sil": "rest",
}

# ARPAbet (flite, festival: lower case) → viseme, the usual Oculus grouping.
ARPABET = {
    **dict.fromkeys(["p", "b", "m"], "PP"), **dict.fromkeys(["f", "v"], "FF"),
    **dict.fromkeys(["th", "dh"], "TH"), **dict.fromkeys(["t", "d"], "DD"),
    **dict.fromkeys(["k", "g", "ng"], "kk"), **dict.fromkeys(["ch", "jh", "sh", "zh"], "CH"),
    **dict.fromkeys(["s", "z"], "SS"), **dict.fromkeys(["n", "l"], "nn"),
    **dict.fromkeys(["r", "er", "er1", "axr"], "RR"),
    **dict.fromkeys(["aa", "ae", "ah", "ay", "aw", "ax"], "aa"),
    **dict.fromkeys(["eh", "ey"], "E"), **dict.fromkeys(["ih", "iy", "y"], "ih"),
    **dict.fromkeys(["ao", "ow", "oy"], "oh"), **dict.fromkeys(["uh", "uw", "w"], "ou"),
}


def ipa_viseme(ipa):
    """IPA → viseme by articulation (this script's own table, written from the IPA chart)."""
    s = "".join(c for c in ipa if not unicodedata.combining(c) and c not in "ˈˌːˑʰʲʷ-'" and not c.isdigit())
    if not s:
        return None
    if s == "??":
        return "ou"  # eSpeak NG's German UR (ʊɐ̯, "wurde", "durch"), for which it writes no IPA
    if s[:2] in ("tʃ", "dʒ", "tɕ", "dʑ", "ʈʂ"):
        return "CH"
    if s[:2] in ("ts", "dz"):
        return "SS"
    c = s[0]
    for chars, v in [("pbmɓβ", "PP"), ("fvɱʋɸ", "FF"), ("θð", "TH"), ("tdʈɖc", "DD"),
                     ("nɳɲlɭʎɫ", "nn"), ("kgɡŋqxɣχʁɰʔ", "kk"), ("ʃʒɕʑʂʐçʝ", "CH"), ("sz", "SS"),
                     ("rɾɹɻɽʀɚɝ", "RR"), ("aɑɐæäʌə", "aa"), ("eɛɜɘɤ", "E"), ("iɪɨj", "ih"),
                     ("oɔɒɵøœ", "oh"), ("uʊʉyʏɯwɥ", "ou")]:
        if c in chars:
            return v
    return None  # h, pauses: not counted


def read_wav(path):
    data = open(path, "rb").read()
    pos, rate, channels, samples = 12, 16000, 1, b""
    while pos + 8 <= len(data):
        kind, size = struct.unpack_from("<4sI", data, pos)
        if kind == b"fmt ":
            _, channels, rate = struct.unpack_from("<HHI", data, pos + 8)
        elif kind == b"data":
            samples = data[pos + 8: pos + 8 + size]
        pos += 8 + size + (size & 1)
    return len(samples) / 2 / channels / rate


def flite(voice, text, wav):
    out = subprocess.run(["flite", "-voice", voice, "-t", text, "-o", wav, "-psdur"],
                         capture_output=True, text=True, check=True).stdout
    phones, start = [], 0.0
    for item in out.split():
        if ":" not in item:
            continue
        phone, end = item.rsplit(":", 1)
        end = float(end)
        phones.append((phone, start, end, ARPABET.get(phone)))
        start = end
    return phones


# Festival's Italian, Finnish, Czech and Catalan voices speak SAMPA (stress as a digit, `#` or
# `pau` a pause).
SAMPA = {"ax": "ə", "E": "ɛ", "O": "ɔ", "dZ": "dʒ", "tS": "tʃ", "S": "ʃ", "Z": "ʒ", "J": "ɲ", "L": "ʎ"}


def sampa_viseme(phone):
    phone = phone.rstrip("0123456789")
    return None if phone in ("#", "pau") else ipa_viseme(SAMPA.get(phone, phone))


def festival(voice, text, wav, work, viseme=ARPABET.get, encoding="latin-1"):
    segs = os.path.join(work, "f.segs")
    script = os.path.join(work, "f.scm")
    quoted = text.replace("\\", "\\\\").replace('"', '\\"')
    with open(script, "w", encoding=encoding) as f:
        f.write(f'({voice})\n(set! utt (Utterance Text "{quoted}"))\n(utt.synth utt)\n'
                f'(utt.save.wave utt "{wav}" \'riff)\n(utt.save.segs utt "{segs}")\n')
    subprocess.run(["festival", "-b", script], check=True, capture_output=True)
    phones, start = [], 0.0
    lines = open(segs).read().split("#", 1)[-1].split("\n")
    for line in lines:
        parts = line.split()
        if len(parts) != 3:
            continue
        end, phone = float(parts[0]), parts[2]
        phones.append((phone, start, end, viseme(phone)))
        start = end
    return phones


class Espeak:
    """eSpeak NG through its own library (ctypes): the sound and its phoneme events."""

    class Event(ctypes.Structure):
        _fields_ = [("type", ctypes.c_int), ("uid", ctypes.c_uint), ("text_position", ctypes.c_int),
                    ("length", ctypes.c_int), ("audio_position", ctypes.c_int),
                    ("sample", ctypes.c_int), ("user_data", ctypes.c_void_p),
                    ("id", ctypes.c_char * 8)]

    def __init__(self):
        self.lib = ctypes.CDLL("libespeak-ng.so.1")
        self.rate = self.lib.espeak_Initialize(2, 0, None, 0x3)
        self.samples, self.events = [], []
        proto = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int,
                                 ctypes.POINTER(Espeak.Event))

        def callback(wav, n, events):
            if n > 0:
                self.samples.extend(wav[:n])
            k = 0
            while events[k].type != 0:
                e = events[k]
                if e.type == 7:
                    self.events.append((e.audio_position, e.id.decode("utf-8", "replace")))
                k += 1
            return 0

        self.callback = proto(callback)
        self.lib.espeak_SetSynthCallback(self.callback)

    def speak(self, voice, text, wav, wpm):
        self.samples, self.events = [], []
        self.lib.espeak_SetVoiceByName(voice.encode())
        self.lib.espeak_SetParameter(1, wpm, 0)
        data = text.encode() + b"\0"
        self.lib.espeak_Synth(data, len(data), 0, 1, 0, 1, None, None)
        self.lib.espeak_Synchronize()
        with open(wav, "wb") as f:
            body = struct.pack(f"<{len(self.samples)}h", *self.samples)
            f.write(b"RIFF" + struct.pack("<I", 36 + len(body)) + b"WAVEfmt "
                    + struct.pack("<IHHIIHH", 16, 1, 1, self.rate, 2 * self.rate, 2, 16)
                    + b"data" + struct.pack("<I", len(body)) + body)
        seconds = len(self.samples) / self.rate
        phones = []
        for k, (ms, name) in enumerate(self.events):
            end = self.events[k + 1][0] / 1000 if k + 1 < len(self.events) else seconds
            label = name or "_"
            phones.append((label, ms / 1000, min(end, ms / 1000 + 0.4) if label != "_" else end,
                           ipa_viseme(name) if name else None))
        return phones


def viseme_rig(faceanim, work):
    """The built-in head with its first 15 targets named as Ready Player Me's visemes."""
    head = os.path.join(work, "head.glb")
    subprocess.run([faceanim, "export-default", "-o", head], check=True, capture_output=True)
    data = open(head, "rb").read()
    length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20: 20 + length])
    rest = data[20 + length:]
    count = 0
    for mesh in gltf["meshes"]:
        names = (mesh.get("extras") or {}).get("targetNames") or []
        renamed = []
        for _ in names:
            renamed.append(f"viseme_{VISEMES[count]}" if count < 15 else f"shape_{count}")
            count += 1
        if names:
            mesh["extras"]["targetNames"] = renamed
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    out = struct.pack("<4sII", b"glTF", 2, 20 + len(text) + len(rest))
    out += struct.pack("<I4s", len(text), b"JSON") + text + rest
    rig = os.path.join(work, "visemes.glb")
    open(rig, "wb").write(out)
    return rig


# Voice types no synthesiser here speaks, made from one that does without moving its phones in
# time (ffmpeg filters on a line at `r` Hz): what each stands for, and the filter graph.
EFFECTS = {
    "child": ("pitch and formants up 40 %, as a child's shorter vocal tract gives",
              lambda r: f"[0:a]asetrate={round(r * 1.4)},aresample={r},atempo={1 / 1.4:.6f}"),
    "deep": ("pitch and formants down 20 %",
             lambda r: f"[0:a]asetrate={round(r * 0.8)},aresample={r},atempo=1.25"),
    "shout": ("24 dB louder, clipped flat where it overflows",
              lambda r: "[0:a]volume=24dB,alimiter=limit=1:level=false"),
    "phone": ("a telephone line: 300-3400 Hz at 8 kHz",
              lambda r: "[0:a]highpass=f=300,lowpass=f=3400,aresample=8000"),
    "quiet": ("30 dB quieter (a distant or badly set microphone)",
              lambda r: "[0:a]volume=-30dB"),
    "dc": ("a DC offset of a tenth of full scale (a cheap sound card)",
           lambda r: "[0:a]dcshift=0.1"),
    # The same noise on every run (ffmpeg's default seed is random: unseeded, P/B/M moved by
    # up to 0.07 between two runs of the same binary).
    "noisy": ("pink noise (a fan, a room) about 15 dB under the voice",
              lambda r: f"anoisesrc=c=pink:a=0.02:r={r}:seed=1[n];[0:a][n]amix=inputs=2:duration=first:normalize=0"),
}


def score(phones, clip, seconds, classes=None):
    """The line's figures (see the module's docs). `classes`, when given, gathers per 10 ms of
    speech the phone's class and the class shown instead where none within ±40 ms matched
    (`{class: [frames, hits, Counter of shown classes]}`)."""
    names = clip["blendshapes"]
    columns = {v: names.index(f"viseme_{v}") for v in VISEMES}
    frames = clip["frames"]
    fps = clip["fps"]

    def dominant(k):
        if k < 0 or k >= len(frames):
            return "rest"
        row = frames[k]
        best = max(VISEMES, key=lambda v: row[columns[v]])
        return CLASS[best] if row[columns[best]] >= 0.2 else "rest"

    hits = total = 0
    for _, start, end, viseme in phones:
        if viseme is None:
            continue
        t = start + 0.005
        while t < end:
            k = round(t * fps)
            total += 1
            hit = any(dominant(k + d) == CLASS[viseme] for d in range(-4, 5))
            hits += hit
            if classes is not None:
                seen = classes.setdefault(CLASS[viseme], [0, 0, collections.Counter()])
                seen[0] += 1
                seen[1] += hit
                if not hit:
                    seen[2][dominant(k)] += 1
            t += 0.01
    closed = bilabials = 0
    for _, start, end, viseme in phones:
        if viseme != "PP":
            continue
        bilabials += 1
        a, b = max(0, round((start - 0.04) * fps)), min(len(frames), round((end + 0.04) * fps) + 1)
        if any(frames[k][columns["PP"]] >= 0.5 for k in range(a, b)):
            closed += 1
    # Closures the rig makes, and those with no bilabial within 40 ms.
    runs = elsewhere = 0
    k = 0
    while k < len(frames):
        if frames[k][columns["PP"]] < 0.5:
            k += 1
            continue
        first = k
        while k < len(frames) and frames[k][columns["PP"]] >= 0.5:
            k += 1
        a, b = first / fps, (k - 1) / fps
        runs += 1
        if not any(v == "PP" and start - 0.04 <= b and a <= end + 0.04 for _, start, end, v in phones):
            elsewhere += 1
    silence = 0.0
    for label, start, end, viseme in phones:
        if viseme is None and label in ("pau", "_", "h#", "sil", "#") and end - start >= 0.3:
            a, b = round((start + 0.1) * fps), round((end - 0.1) * fps)
            for k in range(max(a, 0), min(b, len(frames))):
                silence = max(silence, max(frames[k][columns[v]] for v in VISEMES
                                           if v not in ("sil", "PP")))
    return hits, total, closed, bilabials, silence, elsewhere, runs


def espeak_line(voice, line, wav):
    """eSpeak NG's `voice` saying `line` into `wav`, in an engine of its own (a process): eSpeak
    NG keeps some of one voice's settings into the next, so that in one engine a voice's sound
    depends on the voices spoken before it."""
    run = subprocess.run([sys.executable, os.path.abspath(__file__), "--espeak-line", voice, line, wav],
                         capture_output=True, text=True, check=True)
    return [tuple(p) for p in json.loads(run.stdout)]


def main():
    if len(sys.argv) == 5 and sys.argv[1] == "--espeak-line":
        print(json.dumps(Espeak().speak(sys.argv[2], sys.argv[3], sys.argv[4], 150)))
        return
    parser = argparse.ArgumentParser()
    parser.add_argument("--faceanim", default="target/release/faceanim")
    parser.add_argument("--voices", default="flite:kal,flite:slt,flite:rms,flite:awb,festival:voice_kal_diphone,espeak:en-us+m3")
    parser.add_argument("--lines", type=int, default=len(HARVARD))
    parser.add_argument("--repeat", type=int, default=1,
                        help="say a voice's lines as one recording, all of them this many times "
                             "over (a reading of minutes: 10 is about four)")
    parser.add_argument("--modes", default="text,audio")
    parser.add_argument("--recognise", default="words", help="audio alone: words or phones")
    parser.add_argument("--voice", help="faceanim's --voice (auto, man, woman, child or a warp)")
    parser.add_argument("--ffmpeg-first", action="store_true",
                        help="convert each line to 16 kHz with ffmpeg before faceanim reads it "
                             "(to compare faceanim's own resampling with ffmpeg's)")
    parser.add_argument("--effect", choices=sorted(EFFECTS),
                        help="change each line before faceanim hears it, keeping its timing: "
                             # argparse formats help with %: a literal one is doubled.
                             + "; ".join(f"{k}: {v[0]}" for k, v in sorted(EFFECTS.items())).replace("%", "%%"))
    parser.add_argument("--breakdown", action="store_true",
                        help="also print, per mode, the agreement of each class of phone (closed, "
                             "open, spread, round, lip-teeth, tongue) and what the rig showed "
                             "where it missed: where a voice loses its agreement")
    parser.add_argument("--json")
    args = parser.parse_args()
    # A mode misspelt ("transcript") would otherwise be run as audio alone under its own name.
    unknown = sorted(set(args.modes.split(",")) - {"text", "audio"})
    if unknown:
        parser.error(f"--modes: {', '.join(unknown)} is not a mode (text, audio)")
    work = tempfile.mkdtemp(prefix="faceanim-bench-lipsync-")
    results = []
    try:
        rig = viseme_rig(args.faceanim, work)
        for spec in args.voices.split(","):
            engine, voice = spec.split(":", 1)
            language = "en-us"
            lines = HARVARD[: args.lines]
            if engine == "espeak" and not voice.startswith("en"):
                language = voice.split("+")[0]
                lines = FOREIGN[language]
            elif engine.startswith("festival-"):
                language = engine.split("-", 1)[1]
                lines = FESTIVAL_LINES[language]
            if args.repeat > 1:
                lines = [" ".join(lines * args.repeat)]
            totals = {}
            breakdowns = {}
            for k, line in enumerate(lines):
                wav = os.path.join(work, f"{engine}-{voice}-{k}.wav")
                if engine == "flite":
                    phones = flite(voice, line, wav)
                elif engine == "festival":
                    phones = festival(voice, line, wav, work)
                elif engine.startswith("festival-"):
                    phones = festival(voice, line, wav, work, sampa_viseme,
                                      FESTIVAL_ENCODING.get(language, "latin-1"))
                else:
                    base, plus, variant = voice.partition("+")
                    phones = espeak_line(SPEAKER.get(base, base) + plus + variant, line, wav)
                seconds = read_wav(wav)
                if args.effect:
                    changed = wav[:-4] + f"-{args.effect}.wav"
                    rate = struct.unpack_from("<I", open(wav, "rb").read(28), 24)[0]
                    subprocess.run(["ffmpeg", "-v", "error", "-y", "-i", wav, "-filter_complex",
                                    EFFECTS[args.effect][1](rate), changed], check=True)
                    wav = changed
                if args.ffmpeg_first:
                    converted = wav[:-4] + "-16k.wav"
                    subprocess.run(["ffmpeg", "-v", "error", "-y", "-i", wav, "-ar", "16000",
                                    "-ac", "1", "-acodec", "pcm_s16le", converted], check=True)
                    wav = converted
                for mode in args.modes.split(","):
                    clip_path = os.path.join(work, "clip.json")
                    command = [args.faceanim, "lipsync", wav, "--character", rig, "--fps", "100",
                               "--clip", clip_path, "--language", language]
                    if args.voice:
                        command += ["--voice", args.voice]
                    if mode == "text":
                        command += ["--text", line]
                    else:
                        command += ["--recognise", args.recognise]
                    began = time.monotonic()
                    run = subprocess.run(command, capture_output=True, text=True)
                    wall = time.monotonic() - began
                    if run.returncode != 0:
                        print(f"{spec} line {k} {mode}: {run.stderr.strip()}", file=sys.stderr)
                        continue
                    clip = json.load(open(clip_path))
                    classes = breakdowns.setdefault(mode, {}) if args.breakdown else None
                    hits, total, closed, bilabials, silence, elsewhere, runs = score(
                        phones, clip, seconds, classes)
                    t = totals.setdefault(mode, [0, 0, 0, 0, 0.0, 0.0, 0.0, 0, 0])
                    t[0] += hits; t[1] += total; t[2] += closed; t[3] += bilabials
                    t[4] = max(t[4], silence); t[5] += wall; t[6] += seconds
                    t[7] += elsewhere; t[8] += runs
                    results.append({"voice": spec, "line": k, "mode": mode, "agreement": hits / max(total, 1),
                                    "pbm_closed": closed / max(bilabials, 1), "bilabials": bilabials,
                                    "closures": runs, "closures_elsewhere": elsewhere,
                                    "silence_open": silence, "real_time": wall / seconds,
                                    "notes": run.stderr.strip().splitlines()[:-1]})
            for mode, t in totals.items():
                print(f"{spec:28s} {mode:5s} agreement {t[0] / max(t[1], 1):.3f}  P/B/M closed "
                      f"{t[2]}/{t[3]} = {t[2] / max(t[3], 1):.2f}  closures elsewhere {t[7]}/{t[8]}  "
                      f"silence open ≤ {t[4]:.2f}  "
                      f"{t[5] / t[6]:.2f}× real time", flush=True)
                for name, (frames, hit, shown) in sorted(breakdowns.get(mode, {}).items(),
                                                         key=lambda c: -c[1][0]):
                    missed = ", ".join(f"{c} {n}" for c, n in shown.most_common(3))
                    print(f"    {name:10s} {frames:5d} frames ({frames / max(t[1], 1):4.0%})  "
                          f"agreement {hit / frames:.2f}  costs {(frames - hit) / max(t[1], 1):.3f}"
                          + (f"  (shown instead: {missed})" if missed else ""), flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if args.json:
        json.dump(results, open(args.json, "w"), indent=1, ensure_ascii=False)


if __name__ == "__main__":
    main()
