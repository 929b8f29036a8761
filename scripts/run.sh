#!/usr/bin/env bash
# The README's run command: the studio on the built-in head (or the character given), built
# with everything speech needs. On a machine with apt-get it first installs what lip sync links
# when it is missing — CMU PocketSphinx with its US English models, and eSpeak NG for
# transcripts in any language — so that the build is never made without them; elsewhere it
# says what to install. Arguments go to `faceanim studio` (e.g. scripts/run.sh my.glb).
set -euo pipefail
cd "$(dirname "$0")/.."

missing=()
if command -v dpkg >/dev/null 2>&1; then
  for package in libpocketsphinx-dev pocketsphinx-en-us libespeak-ng-dev; do
    dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
  done
  if ((${#missing[@]})); then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "run: installing ${missing[*]} for lip sync (apt-get)" >&2
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
  fi
else
  echo "run: lip sync needs CMU PocketSphinx 0.8 (libpocketsphinx, with its en-us models) and eSpeak NG (libespeak-ng); install them with your system's packages, or faceanim's speech features will say they are missing" >&2
fi
exec cargo run --release --locked -- studio --open "$@"
