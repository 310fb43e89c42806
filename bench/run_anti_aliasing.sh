#!/usr/bin/env bash
# Anti-aliasing (docs/accuracy.md, "Anti-aliasing"): the thin client's full image at 1, 4 and
# 16 subsamples per pixel (picclient render --samples N on Vulkan, against a CPU-backend
# picserver) and its CPU counterpart at the same N (picref shade --spp N), each against the
# path tracer (picref, which averages each pixel over its samples), per pixel and over 4×4
# blocks; and the client's frame time per N (median of 3). Writes the images and one JSON
# per comparison into ${OUT:-out/anti_aliasing}/ and prints a table.
# Usage: bash bench/run_anti_aliasing.sh [build-dir]
# SPP (default 1024) is the reference's samples per pixel; SAMPLES (default "1 4 16") the
# subsample counts.
set -euo pipefail
BUILD=${1:-build}
OUT=${OUT:-out/anti_aliasing}
SPP=${SPP:-1024}
SAMPLES=${SAMPLES:-1 4 16}
PICBAKE=$BUILD/bake/picbake
PICREF=$BUILD/bake/ref/picref
PICSERVER=$BUILD/server/picserver
PICCLIENT=$BUILD/client/picclient
PICBENCH=$BUILD/bench/picbench
HERE=$(cd "$(dirname "$0")" && pwd)
SCENES=$HERE/../../shared/scenes
mkdir -p "$OUT"

# shellcheck source=server_session.sh
source "$HERE/server_session.sh"

# The relative RMSE of `picbench compare`'s row for block size $2 in its output $1.
rmse_at() { awk -v b="$2x$2" '$1 == b { print $2 }' <<<"$1"; }

# run_case NAME SCENE LIGHTS VIEW SIZE: VIEW is "scene" (the glTF's first camera) or a --camera.
run_case() {
  local name=$1 scene=$2 lights=$3 view=$4 size=$5
  local camera=(--scene-camera 0)
  [ "$view" = scene ] || camera=(--camera "$view")
  local light_args=()
  [ -z "$lights" ] || light_args=(--lights "$lights")
  local bake="$OUT/$name.pic"
  [ -f "$bake" ] || "$PICBAKE" --quiet bake "$scene" -o "$bake" > "$OUT/${name}_bake.log"
  local ref="$OUT/${name}_ref.exr"
  [ -f "$ref" ] || "$PICREF" --quiet "$scene" "${light_args[@]}" "${camera[@]}" --size "$size" \
    --spp "$SPP" --out "$ref"
  start_session "$bake" "$scene" "$OUT/${name}_server.log"
  for n in $SAMPLES; do
    local gpu="$OUT/${name}_gpu_s$n.exr" cpu="$OUT/${name}_cpu_s$n.exr" times=()
    for _ in 1 2 3; do
      local log
      log=$("$PICCLIENT" render --server "$ADDRESS" --session "$SESSION" --token "$TOKEN" \
        "${light_args[@]}" "${camera[@]}" --size "$size" --samples "$n" \
        --cache-dir "$OUT/client_cache" --out "$gpu" 2>&1 >/dev/null)
      times+=("$(sed -E 's/.*samples per pixel, on "[^"]*" ([0-9.]+) ms.*/\1/' <<<"$log")")
    done
    local median
    median=$(printf '%s\n' "${times[@]}" | sort -g | sed -n 2p)
    "$PICREF" shade --quiet "$scene" --bake "$bake" "${light_args[@]}" "${camera[@]}" \
      --size "$size" --spp "$n" --out "$cpu" 2> /dev/null
    local g c gc
    g=$("$PICBENCH" --quiet compare "$gpu" "$ref" --blocks 1 4 --json "$OUT/${name}_gpu_s$n.json")
    c=$("$PICBENCH" --quiet compare "$cpu" "$ref" --blocks 1 4 --json "$OUT/${name}_cpu_s$n.json")
    gc=$("$PICBENCH" --quiet compare "$gpu" "$cpu" --blocks 1)
    printf '| %s %s | %s | %s / %s | %s / %s | %s | %s |\n' "$name" "$size" "$n" \
      "$(rmse_at "$g" 1)" "$(rmse_at "$g" 4)" "$(rmse_at "$c" 1)" "$(rmse_at "$c" 4)" \
      "$(rmse_at "$gc" 1)" "$median"
  done
  stop_server
}

echo "| scene, view | subsamples | client against picref $SPP spp: pixel / 4×4 | picref shade: pixel / 4×4 | client against picref shade | client frame ms (lavapipe) |"
echo "| --- | --- | --- | --- | --- | --- |"
run_case cornell_area "$BUILD/scenes/cornell_area.gltf" "" scene 256x256
run_case furnished_room "$BUILD/scenes/furnished_room.gltf" "" scene 320x240
if [ -f "$SCENES/openarena_oa_rpg3dm2.glb" ]; then
  run_case openarena "$SCENES/openarena_oa_rpg3dm2.glb" "$HERE/lightsets/openarena_sun.json" \
    16,25,-20,18,0,-40,0,1,0,60 320x240
fi
