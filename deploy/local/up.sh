#!/usr/bin/env bash
# up.sh: starts a local pic deployment on 127.0.0.1: a fresh PostgreSQL cluster, N picserver
# replicas that share their sessions through it, and nginx in front of them as the gRPC load
# balancer (consistent hash on the `pic-session` metadata, see nginx.conf.template).
# Everything (data, logs, pid files, configs) lives under STATE_DIR; stop it all with
# `bash deploy/local/down.sh STATE_DIR`.
#
# Usage:
#   bash deploy/local/up.sh STATE_DIR --bake B.pic --scene S.gltf
#                           [--replicas N] [--backend cpu|gpu] [-- PICSERVER_ARGS...]
#
#   STATE_DIR        created; must not exist or be empty
#   --bake, --scene  the bake file and the scene it was made from (passed to every replica)
#   --replicas N     picserver replicas (default 3)
#   --backend B      picserver runtime backend, cpu or gpu (default cpu)
#   -- ARGS...       further arguments given to every picserver
#
# Environment (optional): PICSERVER (default build/server/picserver of this checkout),
# NGINX (default nginx from PATH or /usr/sbin/nginx), PG_BINDIR (directory of initdb and
# pg_ctl; default from PATH, else the newest /usr/lib/postgresql/*/bin).
#
# Writes STATE_DIR/address (nginx's HOST:PORT: what clients connect to), STATE_DIR/dsn,
# STATE_DIR/replica-I.{address,metrics,pid,out,err} for I = 1..N, STATE_DIR/postgres/ and
# STATE_DIR/nginx/. Exit status: 0 when all is up; 2 on a usage error (nothing started);
# 1 when something failed to start (whatever had started is stopped again).
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)"
REPO="$(cd "$HERE/../.." && pwd -P)"
readonly HERE REPO
readonly MARKER=".pic-local-deploy"   # down.sh --remove only deletes directories holding it

STATE_DIR=""
BAKE=""
SCENE=""
REPLICAS=3
BACKEND=cpu
EXTRA_ARGS=()
STARTED=0          # set once something that down.sh must stop may be running

usage() {
    sed -n '/^# Usage:/,/^#   -- ARGS/p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//' >&2
}

# usage_error MESSAGE: a bad invocation; nothing was started.
usage_error() {
    echo "up.sh: $*" >&2
    usage
    exit 2
}

# refuse MESSAGE: cannot start with these arguments or tools; nothing was started.
refuse() {
    echo "up.sh: $*" >&2
    exit 2
}

# die MESSAGE: something failed; the EXIT trap stops what was started.
die() {
    echo "up.sh: $*" >&2
    exit 1
}

log() {
    echo "up.sh: $*"
}

# ---------------------------------------------------------------- arguments and tools

parse_args() {
    while (($#)); do
        case "$1" in
            --bake) (($# >= 2)) || usage_error "--bake needs a value"; BAKE="$2"; shift 2 ;;
            --scene) (($# >= 2)) || usage_error "--scene needs a value"; SCENE="$2"; shift 2 ;;
            --replicas) (($# >= 2)) || usage_error "--replicas needs a value"; REPLICAS="$2"; shift 2 ;;
            --backend) (($# >= 2)) || usage_error "--backend needs a value"; BACKEND="$2"; shift 2 ;;
            -h|--help) usage; exit 0 ;;
            --) shift; EXTRA_ARGS=("$@"); break ;;
            -*) usage_error "unknown option: $1" ;;
            *)
                [[ -z "$STATE_DIR" ]] || usage_error "more than one STATE_DIR: '$STATE_DIR' and '$1'"
                STATE_DIR="$1"; shift ;;
        esac
    done
    [[ -n "$STATE_DIR" ]] || usage_error "missing STATE_DIR"
    [[ -n "$BAKE" ]] || usage_error "missing --bake"
    [[ -n "$SCENE" ]] || usage_error "missing --scene"
    [[ -f "$BAKE" ]] || refuse "bake file not found: $BAKE"
    [[ -f "$SCENE" ]] || refuse "scene file not found: $SCENE"
    [[ "$REPLICAS" =~ ^[1-9][0-9]*$ ]] || usage_error "--replicas must be a positive integer, not '$REPLICAS'"
    [[ "$BACKEND" == cpu || "$BACKEND" == gpu ]] || usage_error "--backend must be cpu or gpu, not '$BACKEND'"
    BAKE="$(realpath -- "$BAKE")"
    SCENE="$(realpath -- "$SCENE")"
}

find_tools() {
    PICSERVER="${PICSERVER:-$REPO/build/server/picserver}"
    [[ -x "$PICSERVER" ]] || refuse "picserver not found at $PICSERVER (build it, or set PICSERVER)"

    NGINX="${NGINX:-$(command -v nginx || echo /usr/sbin/nginx)}"
    [[ -x "$NGINX" ]] || refuse "nginx not found (install it, or set NGINX)"

    if [[ -z "${PG_BINDIR:-}" ]]; then
        if command -v initdb >/dev/null; then
            PG_BINDIR="$(dirname "$(command -v initdb)")"
        else
            PG_BINDIR="$(printf '%s\n' /usr/lib/postgresql/*/bin | sort -V | tail -n 1)"
        fi
    fi
    [[ -x "$PG_BINDIR/initdb" && -x "$PG_BINDIR/pg_ctl" ]] ||
        refuse "initdb/pg_ctl not found (install PostgreSQL, or set PG_BINDIR)"

    AS_PG=()   # prefix that runs a PostgreSQL tool as a user it accepts
    if [[ "$(id -u)" == 0 ]]; then
        id -u postgres >/dev/null 2>&1 ||
            refuse "running as root, but there is no 'postgres' user to run PostgreSQL as"
        AS_PG=(runuser -u postgres --)
    fi
}

# pg CMD ARGS...: runs a PostgreSQL tool (as postgres when we are root) from /, so that it
# does not complain about a working directory it cannot enter.
pg() {
    (cd / && "${AS_PG[@]}" "$PG_BINDIR/$1" "${@:2}")
}

# ---------------------------------------------------------------- state directory

make_state_dir() {
    STATE_DIR="$(realpath -m -- "$STATE_DIR")"
    # The Unix socket STATE_DIR/postgres/.s.PGSQL.PORT must fit in sun_path (107 bytes).
    ((${#STATE_DIR} + 24 <= 107)) ||
        refuse "STATE_DIR '$STATE_DIR' is too long for PostgreSQL's socket path; use a shorter one"
    if [[ -e "$STATE_DIR" ]]; then
        [[ -d "$STATE_DIR" ]] || refuse "STATE_DIR '$STATE_DIR' exists and is not a directory"
        [[ -z "$(ls -A -- "$STATE_DIR")" ]] ||
            refuse "STATE_DIR '$STATE_DIR' is not empty; choose a new directory (or stop and remove the old deployment: bash deploy/local/down.sh '$STATE_DIR' --remove)"
    fi
    mkdir -p -- "$STATE_DIR"
    STATE_DIR="$(cd "$STATE_DIR" && pwd -P)"
    : >"$STATE_DIR/$MARKER"
    if ((${#AS_PG[@]})); then
        chmod 755 "$STATE_DIR"   # postgres must traverse it
    fi
}

# ---------------------------------------------------------------- ports

# port_busy PORT: something accepts connections on 127.0.0.1:PORT.
port_busy() {
    (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null
}

# pick_port: prints a random port in 20000-60999 that nothing accepts on (likely free).
pick_port() {
    local port
    for _ in $(seq 1 50); do
        port=$((20000 + (RANDOM * 32768 + RANDOM) % 41000))
        if ! port_busy "$port"; then
            echo "$port"
            return 0
        fi
    done
    die "found no free port in 20000-60999"
}

# ---------------------------------------------------------------- processes

# alive PID: the process exists and is not a zombie.
alive() {
    local stat
    stat="$(cat "/proc/$1/stat" 2>/dev/null)" || return 1
    stat="${stat##*) }"
    [[ "${stat%% *}" != Z ]]
}

# ---------------------------------------------------------------- PostgreSQL

start_postgres() {
    local dir="$STATE_DIR/postgres"
    local data="$dir/data" logfile="$dir/log" port
    mkdir -p "$dir"
    if ((${#AS_PG[@]})); then
        chown postgres: "$dir"
        "${AS_PG[@]}" test -w "$dir" ||
            die "user postgres cannot write $dir: a parent directory of STATE_DIR is not traversable by others (e.g. /root is 0700); choose a STATE_DIR under /tmp, or chmod o+x the parents"
    fi

    STARTED=1
    log "initdb $data"
    if ! pg initdb --no-sync -A trust -U pic -E UTF8 --locale=C -D "$data" >"$dir/initdb.log" 2>&1; then
        tail -n 20 "$dir/initdb.log" >&2
        die "initdb failed; its log is $dir/initdb.log"
    fi

    for attempt in $(seq 1 10); do
        port="$(pick_port)"
        log "starting PostgreSQL on 127.0.0.1:$port (log: $logfile)"
        if pg pg_ctl -w -t 60 -D "$data" -l "$logfile" \
            -o "-c listen_addresses=127.0.0.1 -p $port -k '$dir'" start \
            </dev/null >"$dir/pg_ctl.out" 2>&1; then
            DSN="postgresql://pic@127.0.0.1:$port/postgres"
            printf '%s\n' "$DSN" >"$STATE_DIR/dsn"
            return 0
        fi
        if [[ -f "$data/postmaster.pid" ]] && grep -q 'did not start in time' "$dir/pg_ctl.out"; then
            break   # still starting after 60 s: not a port problem
        fi
        log "PostgreSQL did not start on port $port (attempt $attempt), trying another port"
    done
    tail -n 20 "$logfile" >&2 2>/dev/null || true
    die "PostgreSQL failed to start; its log is $logfile"
}

# ---------------------------------------------------------------- picserver replicas

start_replica() {
    local i="$1" pid
    local out="$STATE_DIR/replica-$i.out" err="$STATE_DIR/replica-$i.err"
    nohup "$PICSERVER" --bake "$BAKE" --scene "$SCENE" --backend "$BACKEND" \
        --listen 127.0.0.1:0 --db "$DSN" --metrics-listen 127.0.0.1:0 --trusted-proxy 127.0.0.1 --quiet \
        "${EXTRA_ARGS[@]}" </dev/null >"$out" 2>"$err" &
    pid=$!
    printf '%s\n' "$pid" >"$STATE_DIR/replica-$i.pid"
}

# replica_failed I MESSAGE: the tail of replica I's stderr, then die.
replica_failed() {
    local err="$STATE_DIR/replica-$1.err"
    echo "---- last lines of $err:" >&2
    tail -n 20 "$err" >&2 || true
    echo "----" >&2
    die "replica $1 $2; its log is $err"
}

# wait_replica I: waits up to 60 s for `listening on HOST:PORT` on replica I's stdout and the
# metrics line on its stderr; writes replica-I.address and replica-I.metrics.
wait_replica() {
    local i="$1" pid line address metrics deadline
    local out="$STATE_DIR/replica-$i.out" err="$STATE_DIR/replica-$i.err"
    pid="$(cat "$STATE_DIR/replica-$i.pid")"
    deadline=$((SECONDS + 60))
    # `read` succeeds only on a whole line.
    until IFS= read -r line <"$out" 2>/dev/null; do
        alive "$pid" || replica_failed "$i" "(pid $pid) exited before it listened"
        ((SECONDS < deadline)) || replica_failed "$i" "(pid $pid) did not listen within 60 s"
        sleep 0.1
    done
    [[ "$line" =~ ^listening\ on\ (.+:[0-9]+)$ ]] ||
        replica_failed "$i" "printed an unexpected first line: '$line'"
    address="${BASH_REMATCH[1]}"

    deadline=$((SECONDS + 10))
    until metrics="$(sed -n 's|^picserver: metrics on http://\([^/]*\)/metrics.*$|\1|p' "$err" | head -n 1)" &&
        [[ -n "$metrics" ]]; do
        alive "$pid" || replica_failed "$i" "(pid $pid) exited after it listened"
        ((SECONDS < deadline)) || replica_failed "$i" "(pid $pid) printed no 'metrics on' line within 10 s"
        sleep 0.1
    done
    printf '%s\n' "$address" >"$STATE_DIR/replica-$i.address"
    printf '%s\n' "$metrics" >"$STATE_DIR/replica-$i.metrics"
}

start_replicas() {
    local i
    STARTED=1
    log "starting $REPLICAS picserver replicas ($BACKEND backend)"
    for i in $(seq 1 "$REPLICAS"); do
        start_replica "$i"
    done
    for i in $(seq 1 "$REPLICAS"); do
        wait_replica "$i"
    done
}

# ---------------------------------------------------------------- nginx

# nginx_cmd ARGS...: nginx with this deployment's prefix, config and error log.
nginx_cmd() {
    local prefix="$STATE_DIR/nginx"
    "$NGINX" -p "$prefix/" -c "$prefix/nginx.conf" -e "$prefix/logs/error.log" "$@"
}

# render_nginx_conf PORT: STATE_DIR/nginx/nginx.conf from the template.
render_nginx_conf() {
    local port="$1" prefix="$STATE_DIR/nginx" upstreams="" i conf
    for i in $(seq 1 "$REPLICAS"); do
        upstreams+="        server $(cat "$STATE_DIR/replica-$i.address") max_fails=1 fail_timeout=10s;"$'\n'
    done
    upstreams="${upstreams%$'\n'}"
    conf="$(cat "$HERE/nginx.conf.template")"
    # Quoted replacements: taken literally (no & expansion in bash 5.2).
    conf="${conf//@PREFIX@/"$prefix"}"
    conf="${conf//@PORT@/"$port"}"
    conf="${conf//@UPSTREAMS@/"$upstreams"}"
    printf '%s\n' "$conf" >"$prefix/nginx.conf"
    if grep -n '@[A-Z_]*@' "$prefix/nginx.conf" >&2; then
        die "placeholders left unreplaced in $prefix/nginx.conf (from $HERE/nginx.conf.template)"
    fi
}

start_nginx() {
    local prefix="$STATE_DIR/nginx" port pid
    mkdir -p "$prefix/logs" "$prefix/tmp"/{client_body,proxy,fastcgi,uwsgi,scgi}
    chmod 777 "$prefix/tmp" "$prefix/tmp"/*   # workers run as nobody when we are root
    STARTED=1
    for attempt in $(seq 1 10); do
        port="$(pick_port)"
        render_nginx_conf "$port"
        if ! nginx_cmd -t -q </dev/null >"$prefix/logs/test.log" 2>&1; then
            cat "$prefix/logs/test.log" >&2
            die "nginx rejects the generated config $prefix/nginx.conf (see above; log: $prefix/logs/test.log)"
        fi
        log "starting nginx on 127.0.0.1:$port (log: $prefix/logs/error.log)"
        if nginx_cmd </dev/null >"$prefix/logs/start.log" 2>&1; then
            for _ in $(seq 1 50); do
                [[ -s "$prefix/nginx.pid" ]] && break
                sleep 0.1
            done
            pid="$(cat "$prefix/nginx.pid" 2>/dev/null || true)"
            if ! { [[ -n "$pid" ]] && alive "$pid" && port_busy "$port"; }; then
                die "nginx started but is not running/accepting on 127.0.0.1:$port; its log is $prefix/logs/error.log"
            fi
            printf '%s\n' "127.0.0.1:$port" >"$STATE_DIR/address"
            return 0
        fi
        grep -q 'Address already in use' "$prefix/logs/start.log" ||
            { cat "$prefix/logs/start.log" >&2; die "nginx failed to start; its log is $prefix/logs/error.log"; }
        log "port $port is taken (attempt $attempt), trying another port"
    done
    die "nginx found no free port in 10 attempts; its log is $prefix/logs/error.log"
}

# ---------------------------------------------------------------- summary and cleanup

print_summary() {
    local i
    echo
    echo "pic is up: $REPLICAS picserver replica(s) behind nginx"
    echo "  client address : $(cat "$STATE_DIR/address")   (picclient ... --server $(cat "$STATE_DIR/address"))"
    for i in $(seq 1 "$REPLICAS"); do
        printf '  replica %-7s: %s  metrics http://%s/metrics  pid %s\n' "$i" \
            "$(cat "$STATE_DIR/replica-$i.address")" "$(cat "$STATE_DIR/replica-$i.metrics")" \
            "$(cat "$STATE_DIR/replica-$i.pid")"
    done
    echo "  database       : $DSN"
    echo "  state and logs : $STATE_DIR"
    local down="$HERE/down.sh"
    [[ "$PWD" != "$REPO" ]] || down="deploy/local/down.sh"
    printf '  stop with      : bash %q %q\n' "$down" "$STATE_DIR"
}

# on_exit: after a failure, stops whatever was started.
on_exit() {
    local rc=$?
    if ((rc != 0 && STARTED)); then
        echo "up.sh: stopping what was started" >&2
        bash "$HERE/down.sh" "$STATE_DIR" >&2 || true
    fi
    exit "$rc"
}

main() {
    parse_args "$@"
    find_tools
    make_state_dir
    trap on_exit EXIT
    trap 'exit 130' INT TERM
    start_postgres
    start_replicas
    start_nginx
    print_summary
}

main "$@"
