#!/usr/bin/env bash
# Runs every test of faceanim: installs the external checkers if needed (scripts/setup.sh),
# lints, then runs the unit, integration, fuzz, tool (glTF-Validator, Blender) and doc tests.
# The ICT test heads are read from ../shared beside the repository (or $FACEANIM_SHARED).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
cargo clippy --workspace --all-targets --locked -- -D warnings
if cargo nextest --version >/dev/null 2>&1; then
  cargo nextest run --workspace --locked --no-fail-fast
else
  cargo test --workspace --locked --no-fail-fast
fi
cargo test --workspace --doc --locked
