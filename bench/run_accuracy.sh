#!/usr/bin/env bash
# Accuracy of the cache term against the path-traced reference on the test scenes and the
# living room (issue 3), and the one-bounce decomposition of the linked caches' error.
# Writes JSON and side-by-side PNGs into ${OUT:-accuracy}/.
# Usage: bash bench/run_accuracy.sh [build-dir]
set -euo pipefail
BUILD=${1:-build}
OUT=${OUT:-accuracy}
BENCH="$BUILD/bench/picbench --quiet accuracy --out-dir $OUT"
SCENES="$BUILD/scenes"
for links in 128 254; do
  $BENCH --scene "$SCENES/cornell.gltf" --size 128x128 --spp 1024 --probe-samples 512 --links $links \
    --json "$OUT/cornell_links$links.json"
done
# The speed/accuracy trade-off over nL (JSON and a PNG chart).
$BENCH --scene "$SCENES/cornell.gltf" --size 128x128 --spp 1024 --probe-samples 512 \
  --links-sweep 32 64 128 254 512
$BENCH --scene "$SCENES/cornell_area.gltf" --size 128x128 --spp 1024 --probe-samples 512
$BENCH --scene "$SCENES/two_floors.gltf" --camera 1.8,1.6,1.8,-1.5,0.8,-1.5,0,1,0,70 \
  --size 160x96 --spp 512 --probe-samples 512
$BENCH --scene "$SCENES/opposite_colors.gltf" --size 160x96 --spp 512 --probe-samples 512
$BENCH --scene "$(dirname "$0")/../../shared/scenes/living_room_sh3d.glb" \
  --lights "$(dirname "$0")/lightsets/living_room_sun_lamp.json" \
  --camera 0.5,1.7,0.5,4.5,0.5,4.0,0,1,0,70 --size 160x120 --spp 512 --probe-samples 512
# Where the linked caches lose light: one-bounce factors per scene.
LINKS="$BUILD/bench/picbench --quiet links"
$LINKS --scene "$SCENES/cornell.gltf" --json "$OUT/links_cornell.json"
$LINKS --scene "$SCENES/cornell_area.gltf" --json "$OUT/links_cornell_area.json"
$LINKS --scene "$SCENES/two_floors.gltf" --json "$OUT/links_two_floors.json"
$LINKS --scene "$(dirname "$0")/../../shared/scenes/living_room_sh3d.glb" \
  --lights "$(dirname "$0")/lightsets/living_room_sun_lamp.json" --json "$OUT/links_living_room.json"
