#!/usr/bin/env bash
# Fuzzes every target of fuzz/ with libFuzzer (clang, ASan + UBSan) and reports, per target:
# executions, executions a second, coverage (cov: and ft:), corpus size, and any crash.
#
#   bash bench/run_fuzz.sh [--runs N] [--seconds S] [--jobs J] [--targets "gltf frame ..."]
#
# Each target runs until N executions (default 1,000,000) or S seconds (default 0: no limit),
# on a working copy of its committed corpus (fuzz/corpus/NAME; new inputs land in
# out/fuzz/corpus/NAME, not in git), with crashes written to out/fuzz/crashes/NAME. The clang
# build lives in build-fuzz (CC/CXX default clang-19/clang++-19). Writes out/fuzz/fuzz.json.
# Exit status: 0 when no target crashed.
set -euo pipefail
cd "$(dirname "$0")/.."

RUNS=1000000
SECONDS_LIMIT=0
TARGETS="gltf bake_file light_set_json light_set_proto frame session_store"
while (($#)); do
    case "$1" in
        --runs) RUNS="$2"; shift 2 ;;
        --seconds) SECONDS_LIMIT="$2"; shift 2 ;;
        --targets) TARGETS="$2"; shift 2 ;;
        *) echo "run_fuzz.sh: unknown argument $1" >&2; exit 2 ;;
    esac
done

CC="${CC:-clang-19}"
CXX="${CXX:-clang++-19}"
if ! command -v "$CXX" >/dev/null; then
    echo "run_fuzz.sh: $CXX not found: apt install clang-19 libclang-rt-19-dev (scripts/install_deps.sh does)" >&2
    exit 2
fi
BUILD=build-fuzz
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER="$CC" \
    -DCMAKE_CXX_COMPILER="$CXX" -DPIC_FUZZ=ON -DPIC_BUILD_TESTS=OFF >/dev/null
# shellcheck disable=SC2086
cmake --build "$BUILD" -j"$(nproc)" --target $(for t in $TARGETS; do printf 'fuzz_%s ' "$t"; done)

OUT=out/fuzz
mkdir -p "$OUT"
REPORT="$OUT/fuzz.json"
echo "{" >"$REPORT.tmp"
first=1
crashed=0
for t in $TARGETS; do
    corpus="$OUT/corpus/$t"
    crashes="$OUT/crashes/$t"
    rm -rf "$crashes"   # this run's crashes only (keep a reproducer in fuzz/regressions/NAME)
    mkdir -p "$corpus" "$crashes"
    cp -n fuzz/corpus/"$t"/* "$corpus"/ 2>/dev/null || true
    log="$OUT/$t.log"
    start=$SECONDS
    status=0
    # -rss_limit_mb: a scene or bake that makes pic allocate gigabytes is a finding too.
    "$BUILD/fuzz/fuzz_$t" -runs="$RUNS" -max_total_time="$SECONDS_LIMIT" -rss_limit_mb=2048 \
        -timeout=10 -artifact_prefix="$crashes/" -print_final_stats=1 "$corpus" >"$log" 2>&1 || status=$?
    elapsed=$((SECONDS - start))
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
    cov=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)
    ft=$(grep -o 'ft: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)
    files=$(find "$corpus" -type f | wc -l)
    found=$(find "$crashes" -type f | wc -l)
    ((status == 0 && found == 0)) || crashed=1
    printf '%-16s %10s execs %8s/s  cov %6s  ft %6s  corpus %5s  crashes %s  (%s s)\n' "$t" "${execs:-?}" \
        "${rate:-?}" "${cov:-?}" "${ft:-?}" "$files" "$found" "$elapsed"
    ((first)) || echo "," >>"$REPORT.tmp"
    first=0
    printf '  "%s": {"executions": %s, "executions_per_second": %s, "coverage": %s, "features": %s, "corpus": %s, "crashes": %s, "exit": %s, "seconds": %s}' \
        "$t" "${execs:-0}" "${rate:-0}" "${cov:-0}" "${ft:-0}" "$files" "$found" "$status" \
        "$elapsed" >>"$REPORT.tmp"
done
printf '\n}\n' >>"$REPORT.tmp"
mv "$REPORT.tmp" "$REPORT"
echo "written $REPORT"
exit "$crashed"
