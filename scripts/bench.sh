#!/usr/bin/env bash
# Runs every benchmark in bench/ and prints their tables. Usage: scripts/bench.sh [BUILD_DIR]
set -euo pipefail
build=${1:-build}
for b in "$build"/bench/*_bench; do
  [ -x "$b" ] || continue
  echo "== $(basename "$b")"
  "$b"
done
