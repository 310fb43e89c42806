#!/usr/bin/env bash
# Installs dependencies, builds pic and runs the main job: bakes the default scene (the
# generated atrium; pass any .gltf/.glb path to bake that instead), prints the summary, then
# relights the bake with the GPU runtime (a GPU, else lavapipe) and shades a frame from the
# caches, printing the update's timings and where the image is.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
BUILD_DIR=${PIC_BUILD_DIR:-build}
SCENE=${1:-$BUILD_DIR/scenes/atrium.gltf}
OUT_DIR=${PIC_OUT_DIR:-out}
mkdir -p "$OUT_DIR"
OUT="$OUT_DIR/$(basename "${SCENE%.*}").pic"
"$BUILD_DIR/bake/picbake" bake "$SCENE" -o "$OUT"
"$BUILD_DIR/bake/picbake" info "$OUT"
echo "bake written to $OUT (timings in $OUT.timings.json)"
IMAGE="$OUT_DIR/$(basename "${SCENE%.*}")_gpu.png"
"$BUILD_DIR/bake/ref/picref" shade "$SCENE" --bake "$OUT" --backend gpu --scene-camera 0 \
  --size 640x360 --quiet --out "$IMAGE"
echo "frame shaded from the GPU runtime's caches: $IMAGE"
