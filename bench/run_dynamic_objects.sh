#!/usr/bin/env bash
# Dynamic objects (docs/accuracy.md, "Dynamic objects"): a scene baked with --grid-caches
# space, shaded with a box placed in it that the bake never saw (picref shade --object: the
# CPU counterpart of picclient render --object, exact shadow rays) against the path tracer
# with the box inserted (picref --object), and the same view without the box, per pixel and
# over 4×4 blocks, full image and indirect light. Writes images and JSON into
# ${OUT:-out/dynamic_objects}/ and prints a table.
# Usage: bash bench/run_dynamic_objects.sh [build-dir]; SPP (default 2048) is the reference's.
set -euo pipefail
BUILD=${1:-build}
OUT=${OUT:-out/dynamic_objects}
SPP=${SPP:-2048}
PICBAKE=$BUILD/bake/picbake
PICREF=$BUILD/bake/ref/picref
PICBENCH=$BUILD/bench/picbench
BOX=$BUILD/scenes/object_box.gltf
mkdir -p "$OUT"

rmse_at() { awk -v b="$2x$2" '$1 == b { print $2 }' <<<"$1"; }

# run_case NAME SCENE VIEW SIZE TRANSFORM
run_case() {
  local name=$1 scene=$2 view=$3 size=$4 transform=$5
  local camera=(--scene-camera 0)
  [ "$view" = scene ] || camera=(--camera "$view")
  local bake="$OUT/$name.pic"
  [ -f "$bake" ] || "$PICBAKE" --quiet bake "$scene" --grid-caches space -o "$bake" > "$OUT/${name}_bake.log"
  for with in without with; do
    local object=()
    [ "$with" = with ] && object=(--object "$BOX" --transform "$transform")
    for component in full indirect; do
      local ref="$OUT/${name}_${with}_${component}_ref.exr" ours="$OUT/${name}_${with}_${component}_ours.exr"
      [ -f "$ref" ] || "$PICREF" --quiet "$scene" "${camera[@]}" --size "$size" --spp "$SPP" \
        --component "$component" "${object[@]}" --out "$ref" 2> /dev/null
      "$PICREF" shade --quiet "$scene" --bake "$bake" "${camera[@]}" --size "$size" \
        --component "$component" "${object[@]}" --out "$ours" 2> /dev/null
      local e
      e=$("$PICBENCH" --quiet compare "$ours" "$ref" --blocks 1 4 --json "$OUT/${name}_${with}_${component}.json")
      printf '| %s %s | %s box | %s | %s / %s |\n' "$name" "$size" "$with" "$component" \
        "$(rmse_at "$e" 1)" "$(rmse_at "$e" 4)"
    done
  done
}

echo "| scene, view | object | component | relative RMSE against picref $SPP spp: pixel / 4×4 |"
echo "| --- | --- | --- | --- |"
# A box turned in the air in the middle of the Cornell box.
run_case cornell "$BUILD/scenes/cornell.gltf" scene 128x128 0.05,0.55,0.05,20,35,0,0.22
# A box standing on the furnished room's floor.
run_case furnished_room "$BUILD/scenes/furnished_room.gltf" scene 160x120 0.9,0.25,-0.3,0,25,0,0.5
