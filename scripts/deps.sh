#!/usr/bin/env bash
# Installs the Debian 12 packages candi builds and tests with, skipping those already present.
# Idempotent and quiet; works as root or through sudo.
# Usage: scripts/deps.sh [fuzz]   (fuzz: only clang and its sanitizer/libFuzzer runtimes, for
# `make fuzz`; `make test` does not need them)
set -euo pipefail

packages=(
  # toolchain
  g++ cmake ninja-build pkg-config make git ca-certificates
  # core
  libeigen3-dev zlib1g-dev libpng-dev libjpeg-dev libtbb-dev
  # SHA-256 (core/sha256.cc) is libcrypto's: 7x the portable C it replaced (bench/sha256_bench.cc)
  libssl-dev
  # CRSs through PROJ (io/crs.cc; cs2cs checks candi's transforms in tests), E57's XML section
  libproj-dev proj-data proj-bin libpugixml-dev
  # mesh
  libcgal-dev libopenmesh-dev libdxflib-dev
  # sampling
  libnanoflann-dev
  # reconstruction
  colmap libceres-dev libpcl-dev libtorch-dev libopencv-dev
  # COLMAP's feature database, read by candi's own matcher (colmap_database.h)
  libsqlite3-dev
  # render scale-out
  libopenmpi-dev openmpi-bin
  # apps
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev librapidcheck-dev
  # interop tests: the archive opened in the real tools (meshlabserver under xvfb-run, CloudCompare
  # command line with QT_QPA_PLATFORM=offscreen); tests/interop_cli_test.cc
  meshlab cloudcompare xvfb xauth
  # candi view: Boost.Beast/Asio (header-only) serves HTTP and WebSocket; the browser tests drive
  # Debian's chromium headless through the DevTools protocol (tests/view_browser_test.py)
  libboost-dev chromium python3-websocket
)
if [[ ${1:-} == fuzz ]]; then
  packages=(clang-14 libclang-rt-14-dev)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
# Independent readers of candi's LAZ and COPC in tests: npm's laz-perf and copc under node
# (Debian's nodejs and npm where the machine has no node and npm of its own).
if [[ ${1:-} != fuzz ]]; then
  command -v node >/dev/null || missing+=(nodejs)
  command -v npm >/dev/null || missing+=(npm)
fi

# The npm packages of tests/node/package.json into .cache/node (tests find them there). Best
# effort: without the registry the node tests skip, saying so.
node_packages() {
  [[ ${1:-} == fuzz ]] && return 0
  local root dir
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
  dir="$root/.cache/node"
  if cmp -s "$root/tests/node/package.json" "$dir/package.json" && [[ -d $dir/node_modules ]]; then
    return 0
  fi
  mkdir -p "$dir"
  cp "$root/tests/node/package.json" "$dir/package.json"
  if ! command -v npm >/dev/null ||
     ! timeout 600 npm install --prefix "$dir" --no-audit --no-fund --silent >/dev/null 2>&1; then
    rm -f "$dir/package.json"
    echo "deps: npm could not install tests/node/package.json's packages; the node reader tests will skip" >&2
    return 0
  fi
  echo "deps: npm packages of tests/node/package.json in .cache/node" >&2
}

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "deps: all ${#packages[@]} packages present" >&2
  node_packages "${1:-}"
  exit 0
fi

sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
echo "deps: installing ${#missing[@]} packages: ${missing[*]}" >&2
start=$(date +%s)
"${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -qq -o DPkg::Lock::Timeout=600 update >/dev/null
"${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -qq -y --no-install-recommends \
  -o DPkg::Lock::Timeout=600 install "${missing[@]}" >/dev/null
echo "deps: installed in $(( $(date +%s) - start )) s" >&2
node_packages "${1:-}"
