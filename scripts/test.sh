#!/usr/bin/env bash
# Runs every test of faceanim: installs the external checkers if needed (scripts/setup.sh),
# lints, then runs the doc tests and the unit, integration, fuzz and tool (glTF-Validator,
# Blender) tests. The ICT test heads are read from ../shared beside the repository (or
# $FACEANIM_SHARED).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p target

# What faceanim's build links (PocketSphinx, eSpeak NG) first: their bindings' build scripts
# look for them. The rest (Blender, Chromium, the Node tools, the Python peers; downloads and
# dpkg, mostly waiting) installs while faceanim builds.
scripts/setup.sh libraries
scripts/setup.sh >target/setup.log 2>&1 &
setup=$!
scripts/check-layers.sh
scripts/check-circles.py

# One build serves the lints and the tests: faceanim's own crates are compiled by clippy-driver
# (rustc with clippy's lints, every warning an error), the dependencies by rustc once, instead of
# a `cargo clippy` pass that checks every dependency a second time. Every target clippy's
# --all-targets covers is built: libraries, binaries, tests and examples by the test build,
# benches by `cargo build --benches`.
RUSTC_WORKSPACE_WRAPPER="$(command -v clippy-driver)"
export RUSTC_WORKSPACE_WRAPPER
export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"
nextest=false
cargo nextest --version >/dev/null 2>&1 && nextest=true
if $nextest; then
  cargo nextest run --workspace --locked --no-run
else
  cargo test --workspace --locked --no-run
fi
cargo build --workspace --benches --locked

if ! wait "$setup"; then
  cat target/setup.log >&2
  echo "test.sh: scripts/setup.sh failed (its output is above)" >&2
  exit 1
fi
cat target/setup.log
# The page's modules parse (a syntax error would only show as a page that never loads).
for module in web/*.js; do
  node --input-type=module --check <"$module" || { echo "test.sh: $module does not parse" >&2; exit 1; }
done
cargo test --workspace --doc --locked
# The recogniser as a machine without Debian's library builds it (macOS, Windows, other Linux):
# PocketSphinx 5.1 compiled from its source package (fetched by setup.sh) with its own models,
# tested on its own (real speech decoded into phones, a word search, a grammar), in a target
# folder of its own so that the main build keeps Debian's.
FACEANIM_POCKETSPHINX_SOURCE="$PWD/target/pocketsphinx-5.1.0" CARGO_TARGET_DIR=target/source-build \
  cargo test -p faceanim-sphinx-sys --locked
# The kernel faceanim adds to its vendored tract-tflite, against its contract in scalar code.
cargo test -p tract-tflite --lib --locked faceanim
# Last, so that the run ends on the summary of every test.
if $nextest; then
  cargo nextest run --workspace --locked --no-fail-fast
else
  cargo test --workspace --locked --no-fail-fast
fi
