#!/usr/bin/env bash
# Installs what the test suite checks faceanim's files with, when it is missing:
#   - Blender 3.4 and NumPy for its glTF importer (Debian packages), to open exports as users do;
#   - Node.js and the Khronos glTF-Validator (npm, pinned in tools/package-lock.json);
#   - ffmpeg, which faceanim uses to read video and the tests use to make videos, and
#     ExifTool, which marks the tests' photos turned as a phone's camera does (EXIF);
#   - Chromium (Debian) and playwright-core (npm), to test the studio in a real browser, and iwer
#     (npm), the emulated Meta Quest 3 its VR test runs in;
#   - gltfpack and @gltf-transform/cli (npm), which compress the tests' avatars as people's
#     downloads are (meshopt, quantization, Draco), and meshoptimizer's own decoder (npm), with
#     which three.js opens the meshopt-compressed exports, and three.js itself (npm `three`),
#     whose GLTFExporter saves a test avatar again as web editors do;
#   - python-osc (PyPI), the independent OSC implementation the VMC tests talk to, and
#     pylivelinkface (PyPI), an independent Live Link Face sender for the phone tests;
#   - CMU PocketSphinx (Debian: the library lip sync links, its US English models, and its
#     test data — real LibriVox speech with transcripts) and flite, the synthetic voices whose
#     exact phone timings the viseme accuracy test compares with;
#   - eSpeak NG (Debian: the library lip sync in other languages links, and its program), which
#     speaks a transcript in its language to align it by synthesis;
#   - MeCab with IPADIC (Debian), which reads a Japanese transcript's kanji into kana;
#   - PocketSphinx 5.1's source package (PyPI, into target/), which the tests compile the
#     recogniser from as a machine without Debian's packages does.
# Safe to run again: it installs only what is not there. `scripts/setup.sh libraries` installs
# only what faceanim's build links (PocketSphinx, eSpeak NG: their bindings' build scripts look
# for them), so that the rest can install while faceanim builds (scripts/test.sh); without
# dpkg it fetches PocketSphinx's source package instead (scripts/fetch-pocketsphinx.py).
set -euo pipefail
cd "$(dirname "$0")/.."

# What faceanim's build links: CMU PocketSphinx with its US English models (lip sync's
# recogniser) and eSpeak NG (transcripts in any language).
libraries=(libpocketsphinx-dev pocketsphinx-en-us libespeak-ng-dev)

packages=()
# Adds to `packages` those of the Debian packages named that are not installed.
want() {
  local package
  for package in "$@"; do
    dpkg -s "$package" >/dev/null 2>&1 || packages+=("$package")
  done
}

apt_install() {
  (($#)) || return 0
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "setup: installing $* (apt-get)"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" >/dev/null
}

# PocketSphinx compiled from its PyPI source package, which carries the US English models too
# (scripts/fetch-pocketsphinx.py), where Debian's packages are not to be had.
from_sources() {
  local python
  python=$(command -v python3 || command -v python || true)
  if [ -n "$python" ]; then
    "$python" scripts/fetch-pocketsphinx.py || echo "setup: PocketSphinx's sources could not be fetched: lip sync will say the recogniser is missing" >&2
  else
    echo "setup: fetching PocketSphinx's sources needs Python 3: without them lip sync will say the recogniser is missing" >&2
  fi
}

if [ "${1:-}" = libraries ]; then
  if ! command -v dpkg >/dev/null 2>&1; then
    # No Debian packages here (macOS, Windows, another Linux).
    from_sources
    echo "setup: transcripts in languages other than English are aligned by eSpeak NG's library: install it with your system's packages (brew install espeak-ng; Windows: the espeak-ng installer) or those lines are aligned by the recogniser (English) or not at all" >&2
    echo "setup: a Japanese transcript written in kanji is read by MeCab with IPADIC: install them with your system's packages (brew install mecab mecab-ipadic) or such lines are heard without their transcript" >&2
    exit 0
  fi
  want "${libraries[@]}"
  if ! apt_install "${packages[@]}"; then
    # No root and no sudo, or no apt-get: the recogniser from its sources all the same.
    echo "setup: apt-get could not install ${packages[*]}" >&2
    dpkg -s libpocketsphinx-dev pocketsphinx-en-us >/dev/null 2>&1 || from_sources
  fi
  # The programs faceanim runs: ffmpeg for video and compressed sound, libheif's heif-convert
  # for phones' HEIC photos, MeCab with IPADIC for Japanese written in kanji. Apart from the
  # libraries, so that one missing here never costs the build its recogniser; faceanim says
  # how to install each where it is missing.
  programs=()
  command -v ffmpeg >/dev/null 2>&1 || programs+=(ffmpeg)
  command -v heif-convert >/dev/null 2>&1 || command -v heif-dec >/dev/null 2>&1 || programs+=(libheif-examples)
  # MeCab with IPADIC reads a Japanese transcript's kanji into kana.
  command -v mecab >/dev/null 2>&1 || programs+=(mecab)
  packages=()
  want mecab-ipadic-utf8
  programs+=("${packages[@]}")
  apt_install "${programs[@]}" || echo "setup: apt-get could not install ${programs[*]}: video, HEIC photos and Japanese in kanji will say how to install them" >&2
  exit 0
fi

command -v blender >/dev/null 2>&1 || packages+=(blender)
want python3-numpy
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)
command -v ffmpeg >/dev/null 2>&1 || packages+=(ffmpeg)
# ExifTool: it turns the tests' photos as a phone's camera stores them (EXIF orientation).
command -v exiftool >/dev/null 2>&1 || packages+=(libimage-exiftool-perl)
# libheif's programs: faceanim reads phones' HEIC photos through heif-convert, and the tests make
# them with heif-enc.
command -v heif-enc >/dev/null 2>&1 || packages+=(libheif-examples)
want "${libraries[@]}" pocketsphinx-testdata flite espeak-ng mecab mecab-ipadic-utf8
command -v chromium >/dev/null 2>&1 || packages+=(chromium)
apt_install "${packages[@]}"

if [ ! -d tools/node_modules/gltf-validator ] || [ ! -d tools/node_modules/playwright-core ] || [ ! -d tools/node_modules/gltfpack ] || [ ! -d tools/node_modules/@gltf-transform/cli ] || [ ! -d tools/node_modules/iwer ] || [ ! -d tools/node_modules/three ] || [ ! -d tools/node_modules/@pixiv/three-vrm-animation ] || [ tools/package-lock.json -nt tools/node_modules/.package-lock.json ]; then
  echo "setup: installing the glTF-Validator, playwright-core, gltfpack, gltf-transform, three.js's exporter and pixiv's three-vrm (npm ci in tools/)"
  (cd tools && npm ci --no-audit --no-fund --loglevel=error)
fi

# PocketSphinx 5.1's source package (PyPI), for the test of the recogniser machines without
# Debian's get (the script fetches nothing where it is there already).
python3 scripts/fetch-pocketsphinx.py target/pocketsphinx-5.1.0

if ! python3 -c 'import pythonosc' >/dev/null 2>&1; then
  echo "setup: installing python-osc (pip)"
  python3 -m pip install --quiet --disable-pip-version-check python-osc==1.10.2
fi

if ! python3 -c 'import ray, yaml' >/dev/null 2>&1; then
  echo "setup: installing Ray, for the batch driver's test on a local cluster (pip)"
  python3 -m pip install --quiet --disable-pip-version-check ray==2.52.1 pyyaml
fi

if ! python3 -c 'import pylivelinkface' >/dev/null 2>&1; then
  echo "setup: installing pylivelinkface, an independent Live Link Face sender (pip)"
  python3 -m pip install --quiet --disable-pip-version-check pylivelinkface==0.1 timecode==1.5.1
fi
