#!/usr/bin/env bash
# Accuracy of the cache term against the path-traced reference on the test scenes and the
# living room, with the default bake (exposure flux weights, links that read the part they
# see, the visible hierarchy, the error-bound cut) and with paper 000's (--exposure-rays 0
# --link-reads node --link-cut solid-angle --hierarchy agglomerative), the OpenArena level from
# two views, the nL sweep on cornell and the one-bounce decomposition of the linked caches'
# error: the commands of docs/accuracy.md. Writes JSON and side-by-side PNGs into
# ${OUT:-accuracy}/<default|paper>/.
# Usage: bash bench/run_accuracy.sh [build-dir]
set -euo pipefail
BUILD=${1:-build}
OUT=${OUT:-out/accuracy}
SCENES="$BUILD/scenes"
LIVING="$(dirname "$0")/../../shared/scenes/living_room_sh3d.glb"
SUN_LAMP="$(dirname "$0")/lightsets/living_room_sun_lamp.json"
OPENARENA="$(dirname "$0")/../../shared/scenes/openarena_oa_rpg3dm2.glb"
SUN="$(dirname "$0")/lightsets/openarena_sun.json"
for variant in default paper; do
  X=()
  [ "$variant" = paper ] && X=(--exposure-rays 0 --link-reads node --link-cut solid-angle --hierarchy agglomerative --link-final-samples 16)
  A="$BUILD/bench/picbench --quiet accuracy --out-dir $OUT/$variant"
  $A --scene "$SCENES/cornell.gltf" --size 96x96 --spp 512 --probe-samples 512 "${X[@]}"
  $A --scene "$SCENES/cornell_area.gltf" --size 96x96 --spp 512 --probe-samples 512 "${X[@]}"
  $A --scene "$SCENES/two_floors.gltf" --camera 1.8,1.6,1.8,-1.5,0.8,-1.5,0,1,0,70 \
    --size 120x72 --spp 256 --probe-samples 256 "${X[@]}"
  $A --scene "$SCENES/opposite_colors.gltf" --size 120x72 --spp 256 --probe-samples 256 "${X[@]}"
  $A --scene "$SCENES/furnished_room.gltf" --size 120x90 --spp 256 --probe-samples 256 "${X[@]}"
  $A --scene "$SCENES/furnished_study.gltf" --size 120x90 --spp 256 --probe-samples 256 "${X[@]}"
  $A --scene "$LIVING" --lights "$SUN_LAMP" --camera 0.5,1.7,0.5,4.5,0.5,4.0,0,1,0,70 \
    --size 120x90 --spp 256 --probe-samples 256 "${X[@]}"
  # A level under the sun, two views on its roof terraces (into $OUT/<variant>/openarena_<view>).
  for view in "a -5,8.2,-30,-5,7,-10,0,1,0,70" "b 10,7.9,-22,-2,7,-12,0,1,0,70"; do
    $BUILD/bench/picbench --quiet accuracy --out-dir "$OUT/$variant/openarena_${view%% *}" \
      --scene "$OPENARENA" --lights "$SUN" --camera "${view#* }" --size 160x120 --spp 128 \
      --probe-samples 1024 "${X[@]}"
  done
done
# The speed/accuracy trade-off over nL (JSON and a PNG chart).
$BUILD/bench/picbench --quiet accuracy --out-dir "$OUT/default" --scene "$SCENES/cornell.gltf" \
  --size 96x96 --spp 512 --probe-samples 512 --links-sweep 32 64 128 254
# Where the linked caches lose light: one-bounce factors per scene.
LINKS="$BUILD/bench/picbench --quiet links"
$LINKS --scene "$SCENES/cornell.gltf" --json "$OUT/links_cornell.json"
$LINKS --scene "$SCENES/cornell_area.gltf" --json "$OUT/links_cornell_area.json"
$LINKS --scene "$SCENES/two_floors.gltf" --json "$OUT/links_two_floors.json"
$LINKS --scene "$LIVING" --lights "$SUN_LAMP" --json "$OUT/links_living_room.json"
$LINKS --scene "$OPENARENA" --lights "$SUN" --json "$OUT/links_openarena.json"
$LINKS --scene "$OPENARENA" --lights "$SUN" --one-sided-truth --json "$OUT/links_openarena_one_sided.json"
$LINKS --scene "$SCENES/furnished_room.gltf" --one-sided-truth --json "$OUT/links_furnished_room_one_sided.json"
