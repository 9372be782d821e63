#!/usr/bin/env bash
# Installs the test-only npm packages of the independent-reader tests (tests/node/): laz-perf (the
# WASM build of laz-perf, reads candi's LAZ) and copc (copc.js, reads candi's COPC), pinned, into
# one folder; the tests find them through NODE_PATH and skip, saying so, when they are absent.
# Needs Debian's nodejs and npm (apt-get install nodejs npm). Idempotent.
# Usage: scripts/node_test_deps.sh [folder]   (default build/node); then
#        export NODE_PATH=<folder>/node_modules
set -euo pipefail

folder="${1:-build/node}"
mkdir -p "$folder"
if ! command -v npm > /dev/null; then
  echo "npm is absent: apt-get install nodejs npm" >&2
  exit 1
fi
(cd "$folder" && npm install --no-audit --no-fund --silent laz-perf@0.0.7 copc@0.0.8)
echo "export NODE_PATH=$(cd "$folder" && pwd)/node_modules"
