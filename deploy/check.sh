#!/usr/bin/env bash
# check.sh: checks the files of deploy/ with the tools this machine has, one line per check:
#   PASS  what          the check ran and passed
#   FAIL  what: why     the check ran and failed (its output follows, indented)
#   SKIP  what: why     a tool it needs is missing; does not change the exit status
# Exit status: 0 when nothing failed, 1 otherwise.
#
#   bash deploy/check.sh
#
# What it checks:
#   - kubectl kustomize renders deploy/k8s, deploy/k8s/bake and deploy/overlays/example (the latter with
#     db.env.example and api-keys.example as its db.env and api-keys, in a copy)
#   - nginx -t accepts deploy/compose/nginx.conf and deploy/k8s/nginx.conf, run on copies in a
#     temporary directory where the host names are 127.0.0.1, the paths (pid, temp dirs) lie in
#     that directory, and, on an nginx older than the config needs, the newer syntax is turned
#     into its older form (each such change is printed)
#   - the YAML files parse (python3 with PyYAML), compose.yaml has the expected services, the
#     Indexed Job of deploy/k8s/bake has as many completions as PIC_SHARDS, and
#     `docker compose config` / `podman-compose config` accept it where they are installed
#   - deploy/Containerfile copies every source directory the top-level CMakeLists.txt adds
#   - deploy/Containerfile installs the Debian package of every shared library that the built
#     binaries (build/server/picserver, build/bake/picbake, build/client/picclient) link
set -uo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)"
REPO="$(cd "$HERE/.." && pwd -P)"
TMP="$(mktemp -d "${TMPDIR:-/tmp}/pic-deploy-check.XXXXXX")"
trap 'rm -rf "$TMP"' EXIT

FAILURES=0

pass() { printf 'PASS  %s\n' "$1"; }
skip() { printf 'SKIP  %s\n' "$1"; }
# fail WHAT [OUTPUT_FILE]: the check failed; the file's lines follow, indented.
fail() {
    printf 'FAIL  %s\n' "$1"
    if [[ -n "${2:-}" && -s "$2" ]]; then
        sed 's/^/        /' "$2" | head -n 40
    fi
    FAILURES=$((FAILURES + 1))
}

# version_ge A B: version A >= version B.
version_ge() {
    [[ "$(printf '%s\n%s\n' "$1" "$2" | sort -V | head -n 1)" == "$2" ]]
}

# ---------------------------------------------------------------- kustomize

check_kustomize() {
    if ! command -v kubectl >/dev/null; then
        skip "kubectl kustomize deploy/k8s: kubectl not installed"
        skip "kubectl kustomize deploy/k8s/bake: kubectl not installed"
        skip "kubectl kustomize deploy/overlays/example: kubectl not installed"
        return
    fi
    local out="$TMP/kustomize.out"
    local dir
    for dir in k8s k8s/bake; do
        if kubectl kustomize "$HERE/$dir" >"$TMP/rendered.yaml" 2>"$out"; then
            pass "kubectl kustomize deploy/$dir ($(grep -c '^kind:' "$TMP/rendered.yaml") resources)"
        else
            fail "kubectl kustomize deploy/$dir" "$out"
        fi
    done

    # The overlay reads db.env, which is not in git: render a copy with the example's values.
    mkdir -p "$TMP/kdeploy/overlays"
    cp -r "$HERE/k8s" "$TMP/kdeploy/k8s"
    cp -r "$HERE/overlays/example" "$TMP/kdeploy/overlays/example"
    cp "$HERE/overlays/example/db.env.example" "$TMP/kdeploy/overlays/example/db.env"
    cp "$HERE/overlays/example/api-keys.example" "$TMP/kdeploy/overlays/example/api-keys"
    if kubectl kustomize "$TMP/kdeploy/overlays/example" >"$TMP/overlay.yaml" 2>"$out"; then
        pass "kubectl kustomize deploy/overlays/example ($(grep -c '^kind:' "$TMP/overlay.yaml") resources)"
    else
        fail "kubectl kustomize deploy/overlays/example" "$out"
    fi
}

# ---------------------------------------------------------------- nginx -t

# nginx_test NAME SRC_CONF SED_SCRIPT: runs nginx -t on a copy of SRC_CONF in $TMP/NAME,
# edited by SED_SCRIPT (plus the /tmp -> $TMP/NAME path change).
nginx_test() {
    local name="$1" src="$2" script="$3"
    local dir="$TMP/nginx-$name"
    mkdir -p "$dir/logs"
    sed -e "s#/tmp/#$dir/#g" -e "$script" "$src" >"$dir/nginx.conf"
    if "$NGINX" -t -p "$dir/" -c "$dir/nginx.conf" -e "$dir/error.log" >"$dir/test.out" 2>&1; then
        pass "nginx -t deploy/${src#"$HERE/"} (nginx $NGINX_VERSION${NOTES[$name]:+; ${NOTES[$name]}})"
    else
        fail "nginx -t deploy/${src#"$HERE/"} (nginx $NGINX_VERSION)" "$dir/test.out"
    fi
}

check_nginx() {
    NGINX="$(command -v nginx || { [[ -x /usr/sbin/nginx ]] && echo /usr/sbin/nginx; } || true)"
    if [[ -z "$NGINX" ]]; then
        skip "nginx -t deploy/compose/nginx.conf: nginx not installed"
        skip "nginx -t deploy/k8s/nginx.conf: nginx not installed"
        return
    fi
    NGINX_VERSION="$("$NGINX" -v 2>&1 | sed -n 's|.*nginx/\([0-9.]*\).*|\1|p')"
    declare -gA NOTES=()

    # Both: the `http2` directive is nginx >= 1.25.1; before, http2 is a parameter of listen.
    local common=""
    if ! version_ge "$NGINX_VERSION" 1.25.1; then
        common='/^[[:space:]]*http2 on;/d; s/listen 50051;/listen 50051 http2;/;'
        NOTES[compose]="'http2 on' as 'listen ... http2'"
        NOTES[k8s]="'http2 on' as 'listen ... http2'"
    fi

    # compose: the replicas' names, which only compose's DNS knows.
    nginx_test compose "$HERE/compose/nginx.conf" \
        "$common s/server picserver\([0-9]\):50051/server 127.0.0.1:5005\1/"

    # k8s: the resolver's name; before 1.27.3, no `resolve`/`service=` on upstream servers:
    # the discovered server becomes one fixed address (the rest of the file is checked as is).
    local k8s="$common s/resolver kube-dns\.kube-system\.svc\.cluster\.local /resolver 127.0.0.1 /;"
    if ! version_ge "$NGINX_VERSION" 1.27.3; then
        k8s+=' s/server picserver-headless\.[^ ]* service=grpc resolve /server 127.0.0.1:50051 /;'
        NOTES[k8s]+="${NOTES[k8s]:+, }the 'service=grpc resolve' server as 127.0.0.1:50051 (needs nginx >= 1.27.3)"
    fi
    nginx_test k8s "$HERE/k8s/nginx.conf" "$k8s"
}

# ---------------------------------------------------------------- YAML

# compose_config TOOL...: TOOL -f compose.yaml config accepts deploy/compose.yaml.
compose_config() {
    if (cd "$HERE" && "$@" -f compose.yaml config) >"$TMP/compose.out" 2>&1; then
        pass "$* -f deploy/compose.yaml config"
    else
        fail "$* -f deploy/compose.yaml config" "$TMP/compose.out"
    fi
}

check_yaml() {
    local python
    python="$(command -v python3 || true)"
    if [[ -z "$python" ]] || ! "$python" -c 'import yaml' 2>/dev/null; then
        skip "YAML parses (compose.yaml, prometheus*.yml, k8s/*.yaml): no python3 with PyYAML (Debian: python3-yaml)"
    else
        local out="$TMP/yaml.out"
        if (cd "$HERE" && "$python" - >"$out" 2>&1) <<'EOF'
import glob, sys, yaml
bad = False
parsed = {}
files = ["compose.yaml", "prometheus.yml", "prometheus-kubernetes.yml"] + sorted(
    glob.glob("k8s/*.yaml") + glob.glob("k8s/bake/*.yaml") + glob.glob("overlays/*/*.yaml"))
for f in files:
    try:
        docs = [d for d in yaml.safe_load_all(open(f)) if d is not None]
    except yaml.YAMLError as e:
        print(f"{f}: {e}"); bad = True; continue
    if not docs:
        print(f"{f}: empty"); bad = True
    parsed[f] = docs
if "compose.yaml" not in parsed:
    sys.exit(1)
compose = parsed["compose.yaml"][0]
services = compose.get("services", {})
want = {"postgres", "picserver1", "picserver2", "picserver3", "nginx", "prometheus"}
if set(services) != want:
    print(f"compose.yaml: services {sorted(services)}, expected {sorted(want)}"); bad = True
for name in ("picserver1", "picserver2", "picserver3"):
    s = services.get(name, {})
    args = s.get("command", [])
    for flag in ("--bake", "--scene", "--listen", "--metrics-listen", "--db", "--backend", "--api-keys"):
        if flag not in args:
            print(f"compose.yaml: {name} has no {flag}"); bad = True
    if s.get("image") != "pic:latest" or "healthcheck" not in s:
        print(f"compose.yaml: {name} lacks image pic:latest or its healthcheck"); bad = True
# The sharded bake: as many pods as shards.
for job in parsed.get("k8s/bake/bake-jobs.yaml", []):
    if job.get("spec", {}).get("completionMode") != "Indexed":
        continue
    spec = job["spec"]
    env = {e["name"]: e.get("value") for e in spec["template"]["spec"]["containers"][0].get("env", [])}
    completions, shards = spec.get("completions"), int(env.get("PIC_SHARDS", "0"))
    if completions != shards or not 1 <= spec.get("parallelism", 1) <= completions:
        print(f"k8s/bake/bake-jobs.yaml: completions {completions}, PIC_SHARDS {shards}, "
              f"parallelism {spec.get('parallelism')}: expected completions = PIC_SHARDS >= "
              "parallelism >= 1"); bad = True
sys.exit(1 if bad else 0)
EOF
        then
            pass "YAML parses (compose.yaml, prometheus*.yml, k8s/*.yaml, k8s/bake, overlays), compose.yaml has its 6 services, the bake Job's shard counts agree"
        else
            fail "YAML parses / compose.yaml structure" "$out"
        fi
    fi

    local ran=0
    if command -v docker >/dev/null && docker compose version >/dev/null 2>&1; then
        ran=1
        compose_config docker compose
    fi
    if command -v podman-compose >/dev/null; then
        ran=1
        # podman-compose 1.0.x (Debian 12) has no `config` command.
        if podman-compose -h 2>/dev/null | grep -q '[{,]config[,}]'; then
            compose_config podman-compose
        else
            skip "podman-compose -f deploy/compose.yaml config: this podman-compose ($(podman-compose -v 2>/dev/null | sed -n 's/^podman-compose[a-z]* version *//p' | head -n 1)) has no config command"
        fi
    fi
    ((ran)) || skip "compose config: neither 'docker compose' nor podman-compose installed"
}

# ---------------------------------------------------------------- Containerfile

check_containerfile_sources() {
    local dir missing=()
    while read -r dir; do
        [[ "$dir" == tests || "$dir" == fuzz ]] && continue   # the image builds with PIC_BUILD_TESTS=OFF
        grep -q "^COPY $dir/ $dir/" "$HERE/Containerfile" || missing+=("$dir")
    done < <(sed -n 's/^[[:space:]]*add_subdirectory(\([^/)[:space:]]*\).*/\1/p' "$REPO/CMakeLists.txt" | sort -u)
    if ((${#missing[@]})); then
        printf '%s\n' "the top-level CMakeLists.txt adds these directories, which are not copied: ${missing[*]}" >"$TMP/cf.out"
        fail "Containerfile copies the source directories of CMakeLists.txt" "$TMP/cf.out"
    else
        pass "Containerfile copies every source directory the top-level CMakeLists.txt adds"
    fi
}

check_containerfile_packages() {
    local bins=("$REPO/build/server/picserver" "$REPO/build/bake/picbake" "$REPO/build/client/picclient")
    local b
    for b in "${bins[@]}"; do
        if [[ ! -x "$b" ]]; then
            skip "Containerfile installs the runtime libraries: ${b#"$REPO/"} not built"
            return
        fi
    done
    if ! command -v objdump >/dev/null || ! command -v dpkg >/dev/null; then
        skip "Containerfile installs the runtime libraries: objdump or dpkg missing"
        return
    fi
    local lib path pkg missing=() ldd_out installed
    ldd_out="$(ldd "${bins[@]}" 2>/dev/null)"
    # The package names listed one per line in the runtime stage's apt-get install.
    installed="$(sed -n '/^FROM .*debian:12-slim/,$p' "$HERE/Containerfile" |
        grep -oE '^[[:space:]]+[a-z0-9][a-z0-9.+-]+[[:space:]]*(\\)?$' | tr -d ' \\')"
    while read -r lib; do
        path="$(awk -v l="$lib" '$1 == l && $2 == "=>" { print $3; exit }' <<<"$ldd_out")"
        [[ -n "$path" ]] || { missing+=("$lib(unresolved)"); continue; }
        pkg="$(dpkg -S "$path" 2>/dev/null || dpkg -S "$(readlink -f "$path")" 2>/dev/null)"
        pkg="${pkg%%:*}"
        case "$pkg" in
            libc6|libgcc-s1|libstdc++6) continue ;;   # in every Debian image
        esac
        grep -qxF -- "$pkg" <<<"$installed" || missing+=("$lib->${pkg:-?}")
    done < <(objdump -p "${bins[@]}" | awk '/NEEDED/ { print $2 }' | sort -u)
    if ((${#missing[@]})); then
        printf '%s\n' "not installed by the runtime stage: ${missing[*]}" >"$TMP/pk.out"
        fail "Containerfile installs the package of every linked shared library" "$TMP/pk.out"
    else
        pass "Containerfile installs the package of every shared library the built binaries link"
    fi
}

check_kustomize
check_nginx
check_yaml
check_containerfile_sources
check_containerfile_packages

if ((FAILURES)); then
    echo "check.sh: $FAILURES check(s) failed"
    exit 1
fi
echo "check.sh: all checks that ran passed"
