#!/usr/bin/env bash
# picserver --update-budget-ms on the atrium: from an editor's light change to each of 64
# subscribers holding the first visible change (any part of the version) and the final state,
# for each budget and without one (the baseline of the same run). Bakes the atrium once into
# ${OUT:-out/budget}/, writes budget_atrium.json and its chart budget_atrium.png there.
# Usage: bash bench/run_budget.sh [build-dir]; BACKEND (gpu), CLIENTS (64), BUDGETS
# ("0 5 10 20 40 80"), DURATION (10 s per budget) and RATE (2 changes a second) override.
set -euo pipefail
BUILD=${1:-build}
OUT=${OUT:-out/budget}
mkdir -p "$OUT"
SCENE=$BUILD/scenes/atrium.gltf
BAKE=$OUT/atrium.pic
[ -f "$BAKE" ] || "$BUILD/bake/picbake" --quiet bake "$SCENE" -o "$BAKE" > "$OUT/atrium_bake.log"
# shellcheck disable=SC2086
"$BUILD/bench/picbench" budget --scene "$SCENE" --bake "$BAKE" --backend "${BACKEND:-gpu}" \
  --clients "${CLIENTS:-64}" --budgets ${BUDGETS:-0 5 10 20 40 80} --duration "${DURATION:-10}" \
  --update-rate "${RATE:-2}" --json "$OUT/budget_atrium.json"
echo "chart: $OUT/budget_atrium.png"
