#!/usr/bin/env bash
# The held-out measure in full: 60 stills per renderer (a test run renders 24), the retarget
# map (as every test run measures it) and, beside
# it, the adapter trained with `faceanim adapt` at the product's defaults (about 25 minutes of
# training on two cores, too long for every test run). The figures are printed and kept in
# test-output/heldout/summary.json.
set -euo pipefail
cd "$(dirname "$0")/.."
FACEANIM_HELDOUT_ADAPTER=1 FACEANIM_HELDOUT_STILLS=60 cargo test --locked -p faceanim --test heldout -- --nocapture
