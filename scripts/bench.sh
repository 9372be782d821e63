#!/usr/bin/env bash
# Runs every benchmark in bench/ and prints their tables. Usage: scripts/bench.sh [BUILD_DIR]
set -euo pipefail
build=${1:-build}
for b in "$build"/bench/*_bench; do
  [ -x "$b" ] || continue
  echo "== $(basename "$b")"
  "$b"
done
# candi view under the audit's hostile scenarios: page A's worst camera-to-frame time and the
# server's peak memory in each (the test view_hostile asserts the counts; this prints the times).
echo "== view_hostile"
/usr/bin/python3 "$(dirname "$0")/../tests/browser/view_hostile_test.py" "$build/apps/candi" "$(dirname "$0")/.." --bench
# candi publish: the writer's throughput and bytes, then the site in chromium (software WebGL2).
echo "== candi bench publish"
"$build/apps/candi" bench publish --sizes 1e7 --keep --work-dir candi-bench-view
echo "== publish_browser_bench"
/usr/bin/python3 "$(dirname "$0")/../bench/publish_browser_bench.py" "$build/apps/candi" \
  candi-bench-view/scene-10000000.archive
