#!/usr/bin/env bash
# Installs dependencies, builds pic and runs the whole story on one scene (default: the
# generated atrium under a high sun and a blue sky, with a box placed in the courtyard that
# the bake never saw; pass any .gltf/.glb path, and optionally a light set JSON for it; set
# PIC_CAMERA for scenes without a camera, PIC_OBJECT=FILE and PIC_TRANSFORM=tx,ty,tz,rx,ry,rz,s
# to place an object):
#   bake → picserver (GPU backend: a GPU, else lavapipe) → a session → a light change pushed
#   by an editor → a frame rendered by the thin client from the streamed caches → a short
#   load test; prints the timings, the latencies, where the image is and the session's URL for
#   a browser (run from a terminal, the demo then keeps serving until Enter is pressed).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
BUILD_DIR=${PIC_BUILD_DIR:-build}
SCENE=${1:-$BUILD_DIR/scenes/atrium.gltf}
LIGHTS=${2:-}
OBJECT=${PIC_OBJECT:-}
TRANSFORM=${PIC_TRANSFORM:-}
if [[ $# -eq 0 ]]; then
  LIGHTS=bench/lightsets/atrium_day.json
  OBJECT=${PIC_OBJECT:-$BUILD_DIR/scenes/object_box.gltf}
  TRANSFORM=${PIC_TRANSFORM:--6,0.75,0.5,0,30,0,1.5}
fi
OUT_DIR=${PIC_OUT_DIR:-out}
mkdir -p "$OUT_DIR"
NAME=$(basename "${SCENE%.*}")
BAKE="$OUT_DIR/$NAME.pic"

# A placed object reads the grid caches where it stands: the bake fills the free space with them.
BAKE_ARGS=()
OBJECT_ARGS=()
if [[ -n "$OBJECT" ]]; then
  BAKE_ARGS=(--grid-caches space)
  OBJECT_ARGS=(--object "$OBJECT" --transform "${TRANSFORM:-0,0,0,0,0,0,1}")
fi
"$BUILD_DIR/bake/picbake" bake "$SCENE" "${BAKE_ARGS[@]}" -o "$BAKE"
"$BUILD_DIR/bake/picbake" info "$BAKE"
echo "bake written to $BAKE (timings in $BAKE.timings.json)"

# The server on a free loopback port; its first line says which. Stopped on exit.
SERVER_LOG="$OUT_DIR/${NAME}_server.log"
"$BUILD_DIR/server/picserver" --bake "$BAKE" --scene "$SCENE" --listen 127.0.0.1:0 \
  --web-listen "${PIC_WEB_LISTEN:-127.0.0.1:0}" --backend gpu --quiet > "$SERVER_LOG" 2>&1 &
SERVER_PID=$!
trap 'kill "$SERVER_PID" 2>/dev/null || true; wait "$SERVER_PID" 2>/dev/null || true' EXIT
ADDRESS=""
for _ in $(seq 1 1200); do
  ADDRESS=$(sed -n 's/^listening on //p' "$SERVER_LOG" | head -n 1)
  if [[ -n "$ADDRESS" ]] || ! kill -0 "$SERVER_PID" 2>/dev/null; then break; fi
  sleep 0.1
done
if [[ -z "$ADDRESS" ]]; then echo "picserver did not start; see $SERVER_LOG" >&2; cat "$SERVER_LOG" >&2; exit 1; fi
echo "picserver listening on $ADDRESS (log: $SERVER_LOG)"

SESSION_JSON=$("$BUILD_DIR/client/picclient" session --server "$ADDRESS")
field() { sed -E "s/.*\"$1\":\"([^\"]*)\".*/\1/" <<<"$SESSION_JSON"; }
SESSION=$(field session)
EDITOR=$(field editor_token)
VIEWER=$(field viewer_token)
echo "session $SESSION"

IMAGE="$OUT_DIR/${NAME}_client.png"
# The glTF's first camera, or PIC_CAMERA=ex,ey,ez,tx,ty,tz,ux,uy,uz,fovy for scenes without one.
CAMERA_ARGS=(--scene-camera 0)
if [[ -n "${PIC_CAMERA:-}" ]]; then CAMERA_ARGS=(--camera "$PIC_CAMERA"); fi
LIGHT_ARGS=()
if [[ -n "$LIGHTS" ]]; then LIGHT_ARGS=(--lights "$LIGHTS"); fi
"$BUILD_DIR/client/picclient" render --server "$ADDRESS" --session "$SESSION" --token "$EDITOR" \
  "${LIGHT_ARGS[@]}" "${CAMERA_ARGS[@]}" "${OBJECT_ARGS[@]}" --size 640x360 --out "$IMAGE"

REPORT="$OUT_DIR/${NAME}_load.json"
"$BUILD_DIR/client/picclient" load --server "$ADDRESS" --session "$SESSION" --token "$EDITOR" \
  --clients 8 --duration 4 --update-rate 2 \
  --report "$REPORT"
echo "server log (one line per update): $SERVER_LOG"
echo "frame rendered by the thin client from the streamed caches: $IMAGE"
WEB=$(sed -n 's|^picserver: browsers on \(http://[^ ]*/\) .*|\1|p' "$SERVER_LOG" | head -n 1)
echo "the session in a browser: ${WEB}?session=$SESSION&token=$EDITOR&viewer=$VIEWER (editor)"
echo "                 for viewers: ${WEB}?session=$SESSION&token=$VIEWER"
if [[ -t 0 && -t 1 ]]; then
  read -r -p "serving until Enter is pressed… " _ || true
fi
