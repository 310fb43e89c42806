#!/usr/bin/env bash
# down.sh: stops a local pic deployment started by deploy/local/up.sh: nginx, every picserver
# replica, then PostgreSQL. Idempotent: what is already stopped (or never started) is
# skipped, so it is safe after a partial up.sh, after a replica was killed, or twice.
#
# Usage:
#   bash deploy/local/down.sh STATE_DIR [--remove]
#
#   --remove   then delete STATE_DIR with its data and logs (by default they stay)
#
# Exit status: 0 when nothing of the deployment runs any more; 1 when something could not be
# stopped; 2 on a usage error.
set -euo pipefail

readonly MARKER=".pic-local-deploy"   # written by up.sh into every STATE_DIR it creates

STATE_DIR=""
REMOVE=0
FAILED=0
STOPPED=()   # pids that were ours: wait_reaped waits for their zombies to be gone

usage() {
    sed -n '/^# Usage:/,/^#   --remove/p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//' >&2
}

usage_error() {
    echo "down.sh: $*" >&2
    usage
    exit 2
}

log() {
    echo "down.sh: $*"
}

# fail MESSAGE: remember that something is still running, carry on with the rest.
fail() {
    echo "down.sh: $*" >&2
    FAILED=1
}

parse_args() {
    while (($#)); do
        case "$1" in
            --remove) REMOVE=1; shift ;;
            -h|--help) usage; exit 0 ;;
            -*) usage_error "unknown option: $1" ;;
            *)
                [[ -z "$STATE_DIR" ]] || usage_error "more than one STATE_DIR: '$STATE_DIR' and '$1'"
                STATE_DIR="$1"; shift ;;
        esac
    done
    [[ -n "$STATE_DIR" ]] || usage_error "missing STATE_DIR"
}

# ---------------------------------------------------------------- processes

# alive PID: the process exists and is not a zombie (a killed replica whose parent, up.sh,
# is gone may stay a zombie until init reaps it).
alive() {
    local stat
    [[ "$1" =~ ^[0-9]+$ ]] || return 1
    stat="$(cat "/proc/$1/stat" 2>/dev/null)" || return 1
    stat="${stat##*) }"
    [[ "${stat%% *}" != Z ]]
}

# runs PID NAME: PID is alive and its command line mentions NAME (not a recycled pid).
runs() {
    alive "$1" && tr '\0' ' ' <"/proc/$1/cmdline" 2>/dev/null | grep -q -- "$2"
}

# read_pid FILE: the pid in FILE, or nothing.
read_pid() {
    if [[ -f "$1" ]]; then
        head -n 1 "$1" | tr -dc '0-9'
    fi
}

# wait_gone SECONDS PID...: waits until none of the PIDs is alive; fails if one still is.
wait_gone() {
    local deadline=$((SECONDS + $1)) pid
    shift
    while :; do
        local left=0
        for pid in "$@"; do
            alive "$pid" && left=1
        done
        ((left)) || return 0
        ((SECONDS < deadline)) || return 1
        sleep 0.1
    done
}

# wait_reaped: best effort, up to 3 s, until the processes we stopped have left the process
# table. They were orphans (up.sh, their parent, has exited), so init reaps them, sometimes
# a second or so late; until then `pgrep picserver` still lists them as <defunct>.
wait_reaped() {
    local deadline=$((SECONDS + 3)) pid left
    while ((SECONDS < deadline)); do
        left=0
        for pid in "${STOPPED[@]}"; do
            [[ -e "/proc/$pid" ]] && left=1
        done
        ((left)) || return 0
        sleep 0.1
    done
}

# kill_hard PID...: SIGKILL, then wait a moment for them to go.
kill_hard() {
    kill -KILL "$@" 2>/dev/null || true
    wait_gone 5 "$@"
}

# ---------------------------------------------------------------- nginx

stop_nginx() {
    local prefix="$STATE_DIR/nginx" pid nginx_bin workers=()
    pid="$(read_pid "$prefix/nginx.pid")"
    if [[ -z "$pid" ]] || ! runs "$pid" nginx; then
        return 0
    fi
    mapfile -t workers < <(pgrep -P "$pid" || true)
    STOPPED+=("$pid")
    log "stopping nginx (pid $pid)"
    nginx_bin="$(readlink "/proc/$pid/exe" 2>/dev/null || command -v nginx || echo /usr/sbin/nginx)"
    "$nginx_bin" -p "$prefix/" -c "$prefix/nginx.conf" -e "$prefix/logs/error.log" -s quit \
        </dev/null >/dev/null 2>&1 || kill -QUIT "$pid" 2>/dev/null || true
    # A graceful quit waits for open Subscribe streams: give it 5 s, then end them.
    wait_gone 5 "$pid" "${workers[@]}" && return 0
    kill -TERM "$pid" 2>/dev/null || true
    wait_gone 2 "$pid" "${workers[@]}" && return 0
    log "nginx did not quit; killing it"
    kill_hard "$pid" "${workers[@]}" || fail "nginx (pid $pid) is still running"
}

# ---------------------------------------------------------------- picserver replicas

stop_replicas() {
    local file pid pids=()
    for file in "$STATE_DIR"/replica-*.pid; do
        [[ -e "$file" ]] || continue
        pid="$(read_pid "$file")"
        [[ -n "$pid" ]] || continue
        if runs "$pid" picserver; then
            pids+=("$pid")
            STOPPED+=("$pid")
        elif [[ "$(cat "/proc/$pid/comm" 2>/dev/null)" == picserver ]]; then
            STOPPED+=("$pid")   # killed before, a zombie not reaped yet
        fi
    done
    ((${#pids[@]})) || return 0
    log "stopping picserver replicas (pids ${pids[*]})"
    kill -TERM "${pids[@]}" 2>/dev/null || true
    wait_gone 15 "${pids[@]}" && return 0
    log "replicas still running after 15 s; killing them"
    kill_hard "${pids[@]}" || fail "a picserver replica (of pids ${pids[*]}) is still running"
}

# ---------------------------------------------------------------- PostgreSQL

# pg_ctl_as_owner ARGS...: pg_ctl as the owner of the data directory (postgres when we are
# root), from / so that it can enter its working directory.
pg_ctl_as_owner() {
    local data="$STATE_DIR/postgres/data" bindir
    bindir="${PG_BINDIR:-}"
    if [[ -z "$bindir" ]]; then
        if command -v pg_ctl >/dev/null; then
            bindir="$(dirname "$(command -v pg_ctl)")"
        else
            bindir="$(printf '%s\n' /usr/lib/postgresql/*/bin | sort -V | tail -n 1)"
        fi
    fi
    if [[ "$(id -u)" == 0 ]]; then
        (cd / && runuser -u postgres -- "$bindir/pg_ctl" -D "$data" "$@")
    else
        (cd / && "$bindir/pg_ctl" -D "$data" "$@")
    fi
}

stop_postgres() {
    local data="$STATE_DIR/postgres/data" pid
    pid="$(read_pid "$data/postmaster.pid")"
    if [[ -z "$pid" ]] || ! runs "$pid" postgres; then
        return 0
    fi
    log "stopping PostgreSQL (pid $pid)"
    STOPPED+=("$pid")
    pg_ctl_as_owner -m fast -w -t 30 stop >/dev/null 2>&1 && wait_gone 5 "$pid" && return 0
    log "PostgreSQL did not stop fast; stopping it immediately"
    pg_ctl_as_owner -m immediate -w -t 10 stop >/dev/null 2>&1 && wait_gone 5 "$pid" && return 0
    kill_hard "$pid" || fail "PostgreSQL (pid $pid) is still running; its log is $STATE_DIR/postgres/log"
}

# ---------------------------------------------------------------- main

remove_state_dir() {
    if [[ ! -f "$STATE_DIR/$MARKER" ]]; then
        fail "not removing $STATE_DIR: it holds no $MARKER, so up.sh did not make it"
        return 0
    fi
    rm -rf -- "$STATE_DIR"
    log "removed $STATE_DIR"
}

main() {
    parse_args "$@"
    if [[ ! -d "$STATE_DIR" ]]; then
        log "$STATE_DIR does not exist; nothing to stop"
        exit 0
    fi
    STATE_DIR="$(cd "$STATE_DIR" && pwd -P)"
    stop_nginx
    stop_replicas
    stop_postgres
    wait_reaped
    if ((FAILED)); then
        echo "down.sh: something is still running; $STATE_DIR was left in place" >&2
        exit 1
    fi
    ((REMOVE)) && remove_state_dir
    ((FAILED)) && exit 1
    log "stopped everything of $STATE_DIR"
}

main "$@"
