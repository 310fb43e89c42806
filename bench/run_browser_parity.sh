#!/usr/bin/env bash
# The browser client's image against `picclient render`'s on any bake (the CI test,
# tests/client/browser_test.cpp BrowserParity, does this on the test scenes): a picserver with
# --web-listen on 127.0.0.1, a session, the light set posted as its editor, then the same view,
# size, samples and shadow-map size drawn by picclient render (lavapipe or a GPU) and by a
# headless chromium (SwiftShader WebGL2, client/web/tests/screenshot.mjs), compared by
# `picbench compare` (relative RMSE per pixel and over 4 × 4 and 16 × 16 blocks).
# Usage: bash bench/run_browser_parity.sh BAKE SCENE LIGHTS CAMERA [SIZE]
#   BAKE    the .pic file; SCENE the glTF it was baked from; LIGHTS a light-set JSON file
#   CAMERA  ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy; SIZE WxH (default 320x240)
# Environment: BUILD (default build), OUT (default out/browser_parity/NAME, NAME the bake's
# file name without .pic): browser.png, native.png, compare.json and the logs; SAMPLES
# (default 4), SHADOW_MAP_SIZE (default 1024), CHROMIUM (default /usr/bin/chromium).
set -euo pipefail
die() { echo "run_browser_parity.sh: $*" >&2; exit 1; }
[ $# -ge 4 ] && [ $# -le 5 ] || die "usage: bash bench/run_browser_parity.sh BAKE SCENE LIGHTS CAMERA [SIZE]"
BAKE=$1 SCENE=$2 LIGHTS=$3 CAMERA=$4 SIZE=${5:-320x240}
BUILD=${BUILD:-build}
SAMPLES=${SAMPLES:-4}
SHADOW_MAP_SIZE=${SHADOW_MAP_SIZE:-1024}
NAME=$(basename "${BAKE%.pic}")
OUT=${OUT:-out/browser_parity/$NAME}
HERE=$(cd "$(dirname "$0")" && pwd)
WEB=$HERE/../client/web
for f in "$BAKE" "$SCENE" "$LIGHTS"; do [ -f "$f" ] || die "$f not found"; done
for tool in server/picserver client/picclient bench/picbench; do
  [ -x "$BUILD/$tool" ] || die "$BUILD/$tool is missing (build first, or set BUILD)"
done
[[ $SIZE =~ ^[0-9]+x[0-9]+$ ]] || die "SIZE must be WxH, got $SIZE"
[[ $CAMERA =~ ^[-0-9.eE]+(,[-0-9.eE]+){9}$ ]] || die "CAMERA must be ten numbers ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy, got $CAMERA"
[ -d "$WEB/node_modules/puppeteer-core" ] || die "$WEB/node_modules/puppeteer-core is missing (npm ci in client/web)"
command -v curl > /dev/null || die "curl is not installed"
mkdir -p "$OUT"

"$BUILD/server/picserver" --quiet --bake "$BAKE" --scene "$SCENE" --listen 127.0.0.1:0 \
  --web-listen 127.0.0.1:0 > "$OUT/server.log" 2>&1 &
SERVER_PID=$!
trap 'kill "$SERVER_PID" 2> /dev/null; wait "$SERVER_PID" 2> /dev/null || true' EXIT
ADDRESS= WEBURL=
for _ in $(seq 1200); do
  ADDRESS=$(sed -n 's/^listening on //p' "$OUT/server.log" | head -1)
  WEBURL=$(sed -n 's|^picserver: browsers on \(http://[^ ]*\)/ .*|\1|p' "$OUT/server.log" | head -1)
  [ -n "$ADDRESS" ] && [ -n "$WEBURL" ] && break
  kill -0 "$SERVER_PID" 2> /dev/null || { cat "$OUT/server.log" >&2; die "picserver ended (log: $OUT/server.log)"; }
  sleep 0.1
done
[ -n "$WEBURL" ] || die "picserver did not start within 120 s (log: $OUT/server.log)"

field() { sed -n "s/.*\"$1\": *\"\\([^\"]*\\)\".*/\\1/p"; }
created=$(timeout 60 "$BUILD/client/picclient" session --server "$ADDRESS") || die "picclient session failed"
session=$(echo "$created" | field session)
editor=$(echo "$created" | field editor_token)
posted=$(curl -sS -X POST --data-binary @"$LIGHTS" "$WEBURL/v1/lights?session=$session&token=$editor")
version=$(echo "$posted" | sed -n 's/.*"version": *\([0-9]*\).*/\1/p')
[ -n "$version" ] || die "the server refused $LIGHTS: $posted"

timeout 600 "$BUILD/client/picclient" render --server "$ADDRESS" --session "$session" --token "$editor" \
  --camera "$CAMERA" --size "$SIZE" --samples "$SAMPLES" --shadow-map-size "$SHADOW_MAP_SIZE" \
  --out "$OUT/native.png" --cache-dir "$OUT/cache" > "$OUT/render.log" 2>&1 ||
  { cat "$OUT/render.log" >&2; die "picclient render failed (log: $OUT/render.log)"; }
url="$WEBURL/?session=$session&token=$editor&camera=$CAMERA&size=$SIZE&samples=$SAMPLES"
url+="&shadow_map_size=$SHADOW_MAP_SIZE&ui=0"
timeout 600 node "$WEB/tests/screenshot.mjs" --url "$url" --out "$OUT/browser.png" --version "$version" \
  ${CHROMIUM:+--chromium "$CHROMIUM"} > "$OUT/screenshot.log" 2>&1 ||
  { cat "$OUT/screenshot.log" >&2; die "the browser's screenshot failed (log: $OUT/screenshot.log)"; }
echo "$NAME $SIZE, $SAMPLES spp, shadow maps $SHADOW_MAP_SIZE: the browser against picclient render"
"$BUILD/bench/picbench" compare "$OUT/browser.png" "$OUT/native.png" --json "$OUT/compare.json"
echo "images: $OUT/browser.png $OUT/native.png"
