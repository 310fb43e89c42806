#!/usr/bin/env bash
# The browser transport (docs/stream.md#browsers): for TABS browser tabs beside NATIVE gRPC
# subscribers on one session, how long a light change takes to reach each tab's drawn frame and
# each native subscriber's decoded state, what key and delta frames weigh on the WebSocket, and
# the page's cold load (time to its first drawn frame, bytes over HTTP).
# Usage: bash bench/run_browser.sh [build-dir]
# Per TABS value: a fresh picserver (--web-listen) and session; client/web/tests/latency.mjs
# opens the tabs (headless chromium, SwiftShader WebGL2, each tab in a browser context of its
# own) and, once all have drawn, `picclient load` runs NATIVE subscribers and the editor moving
# the scene's first light RATE times a second for DURATION s. Writes into ${OUT:-out/browser}/
# the bake (made once), per TABS NAME_tabsN.json (NAME_socketsN.json; both reports: .browser,
# .native) with the logs beside it, and prints a markdown table.
# Browser latency, per version: the server accepting the light set → the tab drawing that
# version or a newer one (window.pic.latencies), and → such a frame reaching the page's socket
# handler; native: the editor's SetLights call → a subscriber decoding it (picclient load's
# latency_ms). Either way a version a client skipped counts until a newer one arrived. All tabs
# share one chromium and its one GPU process (software GL), so with many tabs on a small
# machine the drawn figures say as much about the browser as about the transport; versions
# received vs drawn per tab, and MODE=sockets, tell them apart.
# Browser frame bytes are the serialised v1::Frame per WebSocket message; native ones the
# frame's plane bytes.
# MODE=sockets runs client/web/tests/sockets.mjs instead: TABS counts WebSocket subscribers in
# one node process (the page's own stream code) that parse each frame's message but neither
# decompress nor draw it (DECODE=1 decompresses too), so the figures are the transport's:
# received latency and frame bytes, no drawing, no page load.
# Environment: SCENE (default BUILD/scenes/cornell.gltf), TABS ("1 16 64"), NATIVE (16),
# DURATION (10 s), RATE (2 light changes per second), SIZE (160x120), SAMPLES (1),
# BACKEND (cpu or gpu), OPEN (tabs loading at once, default 1), MODE (tabs or sockets), DECODE,
# PAGE_PARAMS (more of the page's URL parameters, e.g. shadow_map_size=256);
# PICBAKE, PICSERVER, PICCLIENT override single binaries, CHROMIUM the browser (default
# /usr/bin/chromium).
set -euo pipefail
BUILD=${1:-build}
OUT=${OUT:-out/browser}
SCENE=${SCENE:-$BUILD/scenes/cornell.gltf}
TABS=${TABS:-1 16 64}
NATIVE=${NATIVE:-16}
DURATION=${DURATION:-10}
RATE=${RATE:-2}
SIZE=${SIZE:-160x120}
SAMPLES=${SAMPLES:-1}
BACKEND=${BACKEND:-cpu}
OPEN=${OPEN:-1}
MODE=${MODE:-tabs}
DECODE=${DECODE:-0}
export SCENE NATIVE DURATION RATE SIZE SAMPLES BACKEND MODE
PICBAKE=${PICBAKE:-$BUILD/bake/picbake}
PICSERVER=${PICSERVER:-$BUILD/server/picserver}
PICCLIENT=${PICCLIENT:-$BUILD/client/picclient}
HERE=$(cd "$(dirname "$0")" && pwd)
WEB=$HERE/../client/web
LATENCY=$WEB/tests/latency.mjs
SOCKETS=$WEB/tests/sockets.mjs

die() { echo "run_browser.sh: $*" >&2; exit 1; }
for tool in "$PICBAKE" "$PICSERVER" "$PICCLIENT"; do
  [ -x "$tool" ] || die "$tool is missing or not executable (build first, or pass the build folder)"
done
[ -f "$SCENE" ] || die "scene $SCENE not found"
command -v node > /dev/null || die "node is not on PATH (the browser driver needs it)"
[ -d "$WEB/node_modules/puppeteer-core" ] || die "$WEB/node_modules/puppeteer-core is missing (npm ci in client/web)"
[ "$MODE" = sockets ] || [ -x "${CHROMIUM:-/usr/bin/chromium}" ] || die "chromium not found at ${CHROMIUM:-/usr/bin/chromium} (set CHROMIUM)"
[[ $MODE == tabs || $MODE == sockets ]] || die "MODE must be tabs or sockets, got $MODE"
[[ $DECODE == 0 || $DECODE == 1 ]] || die "DECODE must be 0 or 1, got $DECODE"
# node's WebSocket: built in from node 22, behind a flag in node 20.
WEBSOCKET_FLAG=
if [ "$MODE" = sockets ] && ! node -e 'process.exit(typeof WebSocket === "function" ? 0 : 1)'; then
  WEBSOCKET_FLAG=--experimental-websocket
  node $WEBSOCKET_FLAG -e 'process.exit(typeof WebSocket === "function" ? 0 : 1)' 2> /dev/null ||
    die "node $(node --version) has no WebSocket (MODE=sockets needs node >= 20.10)"
fi
[[ $BACKEND == cpu || $BACKEND == gpu ]] || die "BACKEND must be cpu or gpu, got $BACKEND"
[[ $SIZE =~ ^[0-9]+x[0-9]+$ ]] || die "SIZE must be WxH, got $SIZE"
mkdir -p "$OUT"
NAME=$(basename "${SCENE%.*}")

SERVER_PID= LATENCY_PID=
stop_all() {
  # latency.mjs closes its chromium on SIGTERM.
  local pid
  for pid in "$LATENCY_PID" "$SERVER_PID"; do
    [ -n "$pid" ] || continue
    kill "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  LATENCY_PID= SERVER_PID=
}
trap stop_all EXIT
trap 'exit 130' INT TERM

# The bake, once.
BAKE=$OUT/$NAME.pic
if [ ! -f "$BAKE" ]; then
  echo "baking $SCENE -> $BAKE" >&2
  timeout 3600 "$PICBAKE" --quiet bake "$SCENE" -o "$BAKE.tmp.pic" > "$OUT/${NAME}_bake.log" 2>&1 ||
    { cat "$OUT/${NAME}_bake.log" >&2; die "picbake failed on $SCENE (log: $OUT/${NAME}_bake.log)"; }
  mv "$BAKE.tmp.pic" "$BAKE"
  if [ -f "$BAKE.tmp.pic.timings.json" ]; then mv "$BAKE.tmp.pic.timings.json" "$BAKE.timings.json"; fi
fi

# start_server LOG: picserver on free loopback ports; sets ADDRESS (gRPC) and WEBURL (browsers).
start_server() {
  local log=$1
  "$PICSERVER" --quiet --bake "$BAKE" --scene "$SCENE" --backend "$BACKEND" \
    --listen 127.0.0.1:0 --web-listen 127.0.0.1:0 > "$log" 2>&1 &
  SERVER_PID=$!
  ADDRESS= WEBURL=
  for _ in $(seq 1200); do
    ADDRESS=$(sed -n 's/^listening on //p' "$log" | head -1)
    WEBURL=$(sed -n 's|^picserver: browsers on \(http://[^ ]*\)/ .*|\1|p' "$log" | head -1)
    [ -n "$ADDRESS" ] && [ -n "$WEBURL" ] && return 0
    kill -0 "$SERVER_PID" 2>/dev/null || break
    sleep 0.1
  done
  cat "$log" >&2
  die "picserver did not start serving gRPC and browsers within 120 s (log: $log)"
}

json_field() { sed -n "s/.*\"$1\": *\"\\([^\"]*\\)\".*/\\1/p"; }

ROWS=()
for tabs in $TABS; do
  [[ $tabs =~ ^[1-9][0-9]*$ ]] || die "TABS holds \"$tabs\", not a tab count"
  base=$OUT/${NAME}_$MODE$tabs
  started=$(date +%s)
  echo "== $NAME: $tabs $MODE, $NATIVE native subscribers, $DURATION s at $RATE changes/s" >&2
  start_server "$base.server.log"
  created=$(timeout 60 "$PICCLIENT" session --server "$ADDRESS") || die "picclient session failed on $ADDRESS"
  session=$(echo "$created" | json_field session)
  editor=$(echo "$created" | json_field editor_token)
  viewer=$(echo "$created" | json_field viewer_token)
  [ -n "$session" ] && [ -n "$editor" ] && [ -n "$viewer" ] || die "picclient session printed no session: $created"
  url="$WEBURL/?session=$session&token=$viewer&size=$SIZE&samples=$SAMPLES&ui=0${PAGE_PARAMS:+&$PAGE_PARAMS}"

  # The tabs: loading (OPEN at a time), then collecting while the load below runs (told when
  # it is over, else for its duration and a margin), then drawing the last version.
  collect=$((DURATION + 20))
  ready_limit=$((120 + 30 * tabs / OPEN))
  rm -f "$base.latency.out"  # a previous run's `ready` must not count
  if [ "$MODE" = tabs ]; then
    node "$LATENCY" --url "$url" --tabs "$tabs" --duration-s "$collect" --open-concurrency "$OPEN" \
      --chromium "${CHROMIUM:-/usr/bin/chromium}" --out "$base.browser.json" > "$base.latency.out" 2> "$base.latency.err" &
  else
    node $WEBSOCKET_FLAG "$SOCKETS" --url "$url" --sockets "$tabs" --duration-s "$collect" --decode "$DECODE" \
      --out "$base.browser.json" > "$base.latency.out" 2> "$base.latency.err" &
  fi
  LATENCY_PID=$!
  waited=0
  until grep -q '^ready$' "$base.latency.out" 2>/dev/null; do
    if ! kill -0 "$LATENCY_PID" 2>/dev/null; then
      cat "$base.latency.err" >&2
      die "the $tabs $MODE ended before they were ready (log: $base.latency.err)"
    fi
    ((waited += 1)) || true
    [ "$waited" -le $((ready_limit * 5)) ] || die "the $tabs $MODE were not ready within $ready_limit s"
    sleep 0.2
  done
  echo "   $MODE ready after $(($(date +%s) - started)) s; light changes start" >&2

  timeout $((DURATION + 180)) "$PICCLIENT" load --server "$ADDRESS" --session "$session" \
    --token "$editor" --clients "$NATIVE" --duration "$DURATION" --update-rate "$RATE" \
    --report "$base.load.json" > "$base.load.log" 2>&1 ||
    { cat "$base.load.log" >&2; die "picclient load failed (log: $base.load.log)"; }
  kill -USR2 "$LATENCY_PID" 2>/dev/null || true  # the changes are over: drain and report

  status=0
  wait "$LATENCY_PID" || status=$?
  LATENCY_PID=
  if [ "$status" -ne 0 ]; then
    cat "$base.latency.err" >&2
    die "the $tabs $MODE failed with status $status (log: $base.latency.err)"
  fi
  stop_all
  wall=$(($(date +%s) - started))

  # Both reports in one file, and the table's row.
  ROWS+=("$(node --input-type=module - "$base" "$tabs" "$wall" <<'EOF'
import { readFileSync, writeFileSync } from 'node:fs';
const [base, tabs, wall] = process.argv.slice(2);
const browser = JSON.parse(readFileSync(`${base}.browser.json`, 'utf8'));
const native = JSON.parse(readFileSync(`${base}.load.json`, 'utf8'));
const env = process.env;
const combined = {
  scene: env.SCENE, mode: env.MODE, clients: Number(tabs), native_subscribers: Number(env.NATIVE),
  duration_s: Number(env.DURATION), update_rate: Number(env.RATE), size: env.SIZE,
  samples: Number(env.SAMPLES), backend: env.BACKEND, wall_s: Number(wall), browser, native,
};
writeFileSync(`${base}.json`, JSON.stringify(combined, null, 2) + '\n');
const kb = (b) => (b / 1024).toFixed(1);
const ms = (l) => `${l.p50.toFixed(0)} / ${l.p99.toFixed(0)}`;
const b = browser, v = b.versions, tabsMode = env.MODE === 'tabs';
if (v.pushed_max !== native.updates)
  console.error(`run_browser.sh: ${tabs} ${env.MODE}: they saw ${v.pushed_max} new versions, ` +
                `the editor pushed ${native.updates}`);
console.log(`| ${tabs} ${env.MODE} | ${tabsMode ? ms(b.latency_ms) : '—'} | ${ms(b.received_latency_ms)} ` +
            `| ${ms(native.latency_ms)} ` +
            `| ${native.updates} / ${v.received.mean} / ${tabsMode ? `${v.drawn.mean} (min ${v.drawn.min})` : '—'} ` +
            `| ${kb(b.frame_bytes.key.mean)} / ${kb(b.frame_bytes.delta.mean)} ` +
            `(${kb(b.frame_bytes.delta.median)}) ` +
            `| ${kb(native.bytes_per_frame.key)} / ${kb(native.bytes_per_frame.delta)} ` +
            (tabsMode ? `| ${b.load.ms.median.toFixed(0)} / ${b.load.ms.max.toFixed(0)} ` +
                        `| ${(b.load.http_bytes.median / 1048576).toFixed(2)} + ${kb(b.load.first_frame_bytes)} KB |`
                      : '| — | — |'));
EOF
)")
  echo "   done in $wall s -> $base.json" >&2
done

echo
echo "$NAME, $NATIVE native subscribers, $DURATION s at $RATE light changes/s, tabs $SIZE at $SAMPLES spp, $BACKEND backend"
echo
echo "| browser clients | browser drawn p50 / p99 ms | browser received p50 / p99 ms | native decoded p50 / p99 ms | versions pushed / received / drawn per tab | browser key / delta KB mean (delta median) | native key / delta KB | page load ms median / max | page MB over HTTP + first frame |"
echo "|---|---|---|---|---|---|---|---|---|"
printf '%s\n' "${ROWS[@]}"
