#!/usr/bin/env bash
# Texture filtering (docs/accuracy.md, "Texture filtering"): per-pixel and block relative RMSE
# of the CPU shading from caches (picref shade, 1 subsample per pixel) and of the thin client
# (picclient render on Vulkan, against a CPU-backend picserver) against the path tracer
# (picref, which averages each pixel's footprint over its samples), on textured scenes, for the
# direct component (exact light, so only texture filtering and shadow maps differ) and the
# full image. Writes the images and one JSON per comparison into ${OUT:-texture_filtering}/.
# Usage: bash bench/run_texture_filtering.sh [build-dir]
# PICBAKE, PICREF, PICSERVER, PICCLIENT override single binaries (e.g. an older build's);
# PICBENCH likewise (its compare subcommand measures). SPP (default 256) is the reference's.
set -euo pipefail
BUILD=${1:-build}
OUT=${OUT:-out/texture_filtering}
SPP=${SPP:-256}
PICBAKE=${PICBAKE:-$BUILD/bake/picbake}
PICREF=${PICREF:-$BUILD/bake/ref/picref}
PICSERVER=${PICSERVER:-$BUILD/server/picserver}
PICCLIENT=${PICCLIENT:-$BUILD/client/picclient}
PICBENCH=${PICBENCH:-$BUILD/bench/picbench}
HERE=$(cd "$(dirname "$0")" && pwd)
SCENES=$HERE/../../shared/scenes
mkdir -p "$OUT"

# shellcheck source=server_session.sh
source "$HERE/server_session.sh"

# run_case NAME SCENE LIGHTS CAMERA SIZE: one view, both components, both shading paths.
run_case() {
  local name=$1 scene=$2 lights=$3 camera=$4 size=$5
  local bake="$OUT/${name%%-*}.pic"
  [ -f "$bake" ] || "$PICBAKE" --quiet bake "$scene" -o "$bake" > "$OUT/${name%%-*}_bake.log"
  start_session "$bake" "$scene" "$OUT/${name}_server.log"
  for component in direct full; do
    local bounces=()
    [ "$component" = direct ] && bounces=(--bounces 0)
    local ref="$OUT/${name}_${component}_ref.exr"
    [ -f "$ref" ] || "$PICREF" --quiet "$scene" --lights "$lights" --camera "$camera" --size "$size" \
      --spp "$SPP" "${bounces[@]}" --component "$component" --out "$ref"
    "$PICREF" shade --quiet "$scene" --bake "$bake" --lights "$lights" --camera "$camera" \
      --size "$size" --component "$component" --spp 1 --out "$OUT/${name}_${component}_cpu.exr" 2> /dev/null
    "$PICCLIENT" render --server "$ADDRESS" --session "$SESSION" --token "$TOKEN" \
      --lights "$lights" --camera "$camera" --size "$size" --component "$component" --samples 1 \
      --cache-dir "$OUT/client_cache" --out "$OUT/${name}_${component}_gpu.exr" 2> /dev/null
    for path in cpu gpu; do
      echo "== $name $component, $path shading against picref $SPP spp"
      "$PICBENCH" --quiet compare "$OUT/${name}_${component}_${path}.exr" "$ref" \
        --json "$OUT/${name}_${component}_${path}.json" | sed '/^written/d'
    done
  done
  stop_server
}

run_case openarena "$SCENES/openarena_oa_rpg3dm2.glb" "$HERE/lightsets/openarena_sun.json" \
  16,25,-20,18,0,-40,0,1,0,60 320x240
run_case living_room "$SCENES/living_room_sh3d.glb" "$HERE/lightsets/living_room_sun_lamp.json" \
  0.5,1.7,0.5,4.5,0.5,4.0,0,1,0,70 320x240
# The generated checker quad from its scene camera and from just above the floor (grazing).
QUAD=$BUILD/scenes/textured_quad.gltf
QUAD_LIGHTS="$OUT/textured_quad_lights.json"
echo '{"lights":[{"id":"lamp","type":"point","position":[0.0,0.8,0.3],"intensity":1.0}]}' > "$QUAD_LIGHTS"
run_case textured_quad "$QUAD" "$QUAD_LIGHTS" 0,0.9,1.3,0,0.2,-0.2,0,1,0,50 192x192
run_case textured_quad-grazing "$QUAD" "$QUAD_LIGHTS" 0,0.06,0.9,0,0.02,-0.5,0,1,0,50 256x128
