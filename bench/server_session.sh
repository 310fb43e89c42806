# Sourced by the benchmark scripts that drive picserver and picclient (run_texture_filtering.sh,
# run_anti_aliasing.sh): a CPU-backend picserver on a free loopback port with a session on it.
# Needs PICSERVER and PICCLIENT; stops the server on exit.

SERVER_PID=
stop_server() { if [ -n "$SERVER_PID" ]; then kill "$SERVER_PID" 2>/dev/null || true; wait "$SERVER_PID" 2>/dev/null || true; SERVER_PID=; fi; }
trap stop_server EXIT

# start_session BAKE SCENE LOG: serves BAKE for SCENE (its output in LOG) and creates a session;
# sets ADDRESS, SESSION and TOKEN (the editor token). Exits when the server does not start.
start_session() {
  local bake=$1 scene=$2 log=$3
  "$PICSERVER" --quiet --bake "$bake" --scene "$scene" --listen 127.0.0.1:0 --backend cpu \
    > "$log" 2>&1 &
  SERVER_PID=$!
  ADDRESS=
  for _ in $(seq 600); do
    ADDRESS=$(sed -n 's/^listening on //p' "$log" | head -1)
    [ -n "$ADDRESS" ] && break
    sleep 0.1
  done
  [ -n "$ADDRESS" ] || { echo "picserver did not start:"; cat "$log"; exit 1; }
  local created
  created=$("$PICCLIENT" session --server "$ADDRESS")
  TOKEN=$(echo "$created" | sed -n 's/.*"editor_token": *"\([^"]*\)".*/\1/p')
  SESSION=$(echo "$created" | sed -n 's/.*"session": *"\([^"]*\)".*/\1/p')
}
