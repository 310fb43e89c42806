#!/usr/bin/env bash
# Installs dependencies (Debian packages) and builds pic in ./build (Release). Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
BUILD_DIR=${PIC_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=${PIC_BUILD_TYPE:-Release} >/dev/null
cmake --build "$BUILD_DIR" -j"$(nproc)"
# The browser client's packages (client/web/package-lock.json), installed again only when the
# lock file changed.
if [[ ! -f client/web/node_modules/.package-lock.json ||
      client/web/package-lock.json -nt client/web/node_modules/.package-lock.json ]]; then
  (cd client/web && npm ci --no-audit --no-fund --loglevel=error)
fi
