#!/usr/bin/env bash
# Runs every test of faceanim: installs the external checkers if needed (scripts/setup.sh),
# lints, then runs the doc tests and the unit, integration, fuzz and tool (glTF-Validator,
# Blender) tests. The ICT test heads are read from ../shared beside the repository (or
# $FACEANIM_SHARED).
set -euo pipefail
cd "$(dirname "$0")/.."

# The installs (downloads and dpkg, mostly waiting) run while clippy compiles; nothing clippy
# checks needs them (the recogniser's bindings are checked, not linked).
mkdir -p target
scripts/setup.sh >target/setup.log 2>&1 &
setup=$!
cargo clippy --workspace --all-targets --locked -- -D warnings
scripts/check-layers.sh
scripts/check-circles.py
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
# The kernel faceanim adds to its vendored tract-tflite, against its contract in scalar code.
cargo test -p tract-tflite --lib --locked faceanim
# Last, so that the run ends on the summary of every test.
if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run --workspace --locked --no-fail-fast
else
  cargo test --workspace --locked --no-fail-fast
fi
