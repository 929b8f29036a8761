#!/usr/bin/env bash
# The README's run command: the studio on the built-in head (or the character given), built
# with everything speech needs. On a machine with apt-get it first installs what lip sync links
# when it is missing (`scripts/setup.sh libraries`: CMU PocketSphinx with its US English
# models, and eSpeak NG for transcripts in any language), so that the build is never made
# without them, and the programs capture and lip sync run (ffmpeg for video and compressed
# sound, libheif's heif-convert for phones' HEIC photos, MeCab with IPADIC for Japanese in
# kanji); elsewhere (macOS, Windows with Git Bash, another Linux) it fetches PocketSphinx 5.1's
# source package with its models from PyPI, which the build compiles, and says where eSpeak NG
# and MeCab come from. Arguments go to `faceanim studio` (e.g. scripts/run.sh my.glb).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh libraries
exec cargo run --release --locked -- studio --open "$@"
