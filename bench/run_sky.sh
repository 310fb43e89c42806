#!/usr/bin/env bash
# Sky light (docs/accuracy.md, "Sky light"): scenes lit by a sky, relit from a bake's sky
# transfer and shaded from the caches on the CPU (picref shade, exact shadow rays) and on the
# GPU backend (lavapipe here), against the path tracer with the same light set, full image,
# per pixel and over 4×4 blocks. The environment case copies the Cornell box into
# ${OUT}/environment/ beside a ground-and-sky gradient made with oiiotool. Writes images and
# JSON into ${OUT:-out/sky}/ (PNGs of three cases, pic beside the path tracer) and prints a
# table; the rooms and levels also under their sun alone, for what the sky adds.
# Usage: bash bench/run_sky.sh [build-dir]; SPP (default 2048) is the reference's.
set -euo pipefail
BUILD=${1:-build}
OUT=${OUT:-out/sky}
SPP=${SPP:-2048}
PICBAKE=$BUILD/bake/picbake
PICREF=$BUILD/bake/ref/picref
PICBENCH=$BUILD/bench/picbench
LIGHTSETS=$(dirname "$0")/lightsets
mkdir -p "$OUT/environment"

rmse_at() { awk -v b="$2x$2" '$1 == b { print $2 }' <<<"$1"; }

# run_case NAME SCENE LIGHTS SIZE [CAMERA] (default: the scene's first camera)
run_case() {
  local name=$1 scene=$2 lights=$3 size=$4
  local camera=(--scene-camera 0)
  [ -z "${5:-}" ] || camera=(--camera "$5")
  local bake="$OUT/$name.pic" ref="$OUT/${name}_ref.exr"
  [ -f "$bake" ] || "$PICBAKE" --quiet bake "$scene" -o "$bake" > "$OUT/${name}_bake.log"
  [ -f "$ref" ] || "$PICREF" --quiet "$scene" "${camera[@]}" --lights "$lights" --size "$size" \
    --spp "$SPP" --out "$ref" > /dev/null 2>&1
  local row="| $name $size |"
  for backend in cpu gpu; do
    local ours="$OUT/${name}_${backend}.exr"
    "$PICREF" shade --quiet "$scene" --bake "$bake" "${camera[@]}" --lights "$lights" \
      --size "$size" --backend "$backend" --out "$ours" > /dev/null 2>&1
    local e
    e=$("$PICBENCH" --quiet compare "$ours" "$ref" --blocks 1 4 --json "$OUT/${name}_${backend}.json")
    row+=" $(rmse_at "$e" 1) / $(rmse_at "$e" 4) |"
  done
  echo "$row"
}

# A ground-and-sky gradient, +Y up (v = 0 the zenith): blue above, brown below.
ENV_DIR=$OUT/environment
cp "$BUILD/scenes/cornell.gltf" "$BUILD/scenes/cornell.bin" "$ENV_DIR/"
oiiotool --pattern fill:top=0.5,0.65,1.0:bottom=0.25,0.2,0.15 128x64 3 -d float -o "$ENV_DIR/sky.exr"

echo "| scene, size | CPU shading: pixel / 4×4 | GPU backend: pixel / 4×4 |"
echo "| --- | --- | --- |"
run_case cornell_sky "$BUILD/scenes/cornell.gltf" "$LIGHTSETS/sky_only.json" 128x128
run_case cornell_environment "$ENV_DIR/cornell.gltf" "$LIGHTSETS/sky_environment.json" 128x128
# A room lit through its window: the sun and the sky, then the sun alone.
run_case furnished_room_day "$BUILD/scenes/furnished_room.gltf" "$LIGHTSETS/furnished_room_day.json" 160x120
run_case furnished_room_sun "$BUILD/scenes/furnished_room.gltf" "$LIGHTSETS/furnished_room_sun.json" 160x120
run_case atrium_day "$BUILD/scenes/atrium.gltf" "$LIGHTSETS/atrium_day.json" 192x108
run_case atrium_sun "$BUILD/scenes/atrium.gltf" "$LIGHTSETS/atrium_noon_sun.json" 192x108
# Scenes of ../shared/scenes, when present: the living room through its window, and view a
# of docs/accuracy.md's level.
SHARED=$(dirname "$0")/../../shared/scenes
LIVING_ROOM=$SHARED/living_room_sh3d.glb
if [ -f "$LIVING_ROOM" ]; then
  run_case living_room_day "$LIVING_ROOM" "$LIGHTSETS/living_room_day.json" 160x120 0.5,1.7,0.5,4.5,0.5,4.0,0,1,0,70
  run_case living_room_sun "$LIVING_ROOM" "$LIGHTSETS/living_room_sun.json" 160x120 0.5,1.7,0.5,4.5,0.5,4.0,0,1,0,70
fi
OPENARENA=$SHARED/openarena_oa_rpg3dm2.glb
if [ -f "$OPENARENA" ]; then
  run_case openarena_day "$OPENARENA" "$LIGHTSETS/openarena_day.json" 160x120 -5,8.2,-30,-5,7,-10,0,1,0,70
  run_case openarena_sun "$OPENARENA" "$LIGHTSETS/openarena_sun.json" 160x120 -5,8.2,-30,-5,7,-10,0,1,0,70
fi

# PNGs of three cases, pic beside the path tracer: name:exposure.
for case in cornell_environment:2 furnished_room_day:4 atrium_day:2; do
  name=${case%:*}
  oiiotool "$OUT/${name}_cpu.exr" "$OUT/${name}_ref.exr" --mosaic 2x1 --mulc "${case#*:}" \
    --colorconvert linear sRGB -d uint8 -o "$OUT/${name}.png"
done
