#!/usr/bin/env bash
# Installs every Debian package pic needs to build, test and run. Idempotent:
# packages already present are skipped by apt, and `apt-get update` runs only
# when something is missing.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libvulkan-dev mesa-vulkan-drivers vulkan-tools vulkan-validationlayers glslang-tools glslang-dev spirv-tools
  libembree-dev libtbb-dev libmeshoptimizer-dev
  libglm-dev libtinygltf-dev libstb-dev nlohmann-json3-dev
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler libssl-dev
  libopenimageio-dev openimageio-tools fonts-dejavu-core
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev libspdlog-dev libfmt-dev libzstd-dev
  libplplot-dev plplot-driver-cairo
  libsqlite3-dev libpq-dev postgresql nginx libcivetweb-dev
  # libFuzzer (bench/run_fuzz.sh): clang 19, whose libstdc++ mode has std::expected.
  clang-19 libclang-rt-19-dev
)
# The browser client's tests: headless chromium (SwiftShader WebGL2); PIC_NO_BROWSER=1 leaves
# it out where no test runs (the container image's build stage).
if [[ "${PIC_NO_BROWSER:-0}" != 1 ]]; then PACKAGES+=(chromium); fi
# The browser client's npm packages (client/web): Debian's node and npm, unless a node with
# its own npm is installed already.
if ! command -v node >/dev/null; then PACKAGES+=(nodejs); fi
if ! command -v npm >/dev/null; then PACKAGES+=(npm); fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install_deps: all ${#PACKAGES[@]} packages present" >&2
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
echo "install_deps: installing ${missing[*]}" >&2
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
