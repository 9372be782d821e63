#!/usr/bin/env bash
# `make fuzz`: builds the libFuzzer targets of fuzz/ with clang (ASan + UBSan + libFuzzer) in
# build-fuzz/ and runs each for FUZZ_SECONDS (default 60) on its corpus.
# Usage: scripts/fuzz.sh [target...]   (default: every target; names as in fuzz/CMakeLists.txt)
# Environment: FUZZ_SECONDS, FUZZ_BUILD_DIR (build-fuzz), FUZZ_MAX_LEN (65536: longer seeds are
# truncated by libFuzzer), FUZZ_JOBS (ninja jobs, 2), FUZZ_RUNS (stop a target after this many runs,
# even before FUZZ_SECONDS; default: no limit).
# Corpora: build-fuzz/corpus/<target> (grows, kept between runs) seeded from fuzz/corpus/<target>
# (committed seeds), fuzz/regressions/<target> (past findings) and ../shared/data when present
# (staged into build-fuzz/seeds/<target>). Findings (crash-*, leak-*, timeout-*, oom-*) land in
# build-fuzz/findings/<target>/; the script exits non-zero when any target found something.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
build=${FUZZ_BUILD_DIR:-build-fuzz}
seconds=${FUZZ_SECONDS:-60}
max_len=${FUZZ_MAX_LEN:-65536}
jobs=${FUZZ_JOBS:-2}
runs=${FUZZ_RUNS:--1}
all_targets=(ply las laz e57 xyz dxf colmap_bin colmap_text colmap_array scene archive view_protocol)
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=("${all_targets[@]}")

if [[ ! -f $build/build.ninja ]]; then
  CC=clang-14 CXX=clang++-14 cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCANDI_FUZZ=ON -DCANDI_BUILD_RELIEF=OFF -DCANDI_BUILD_TESTS=OFF -DCANDI_BUILD_BENCH=OFF >/dev/null
fi
cmake --build "$build" -j "$jobs" --target "${targets[@]/#/fuzz_}"

# Real files from ../shared/data for a target (stdout: paths), and the COLMAP sparse model joined
# into one input as the harness splits it.
shared=$root/../shared/data
stage_shared() {
  local t=$1 dir=$build/seeds/$1
  rm -rf "$dir" && mkdir -p "$dir"
  [[ -d $shared ]] || return 0
  case $t in
    ply) cp "$shared"/ply/*.ply "$dir"/ 2>/dev/null || true ;;
    las) cp "$shared"/las/*.las "$dir"/ 2>/dev/null || true ;;
    laz) cp "$shared"/las/*.laz "$dir"/ 2>/dev/null || true ;;
    dxf) cp "$shared"/dxf/* "$dir"/ 2>/dev/null || true ;;
    colmap_bin)
      local m=$shared/colmap/sceaux_1600_sparse
      if [[ -f $m/cameras.bin ]]; then
        { cat "$m/cameras.bin"; printf '\n--candi-part--\n'; cat "$m/images.bin"
          printf '\n--candi-part--\n'; cat "$m/points3D.bin"; } >"$dir/sceaux.bin"
      fi ;;
  esac
}

failed=()
for t in "${targets[@]}"; do
  corpus=$build/corpus/$t findings=$build/findings/$t
  mkdir -p "$corpus" "$findings"
  stage_shared "$t"
  seeds=()
  for d in "$root/fuzz/corpus/$t" "$root/fuzz/regressions/$t" "$build/seeds/$t"; do
    [[ -d $d ]] && seeds+=("$d")
  done
  echo "fuzz: $t for ${seconds} s" >&2
  # UBSan reports are findings: stop at the first (with a stack) so libFuzzer keeps the input.
  if ! UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 "$build/fuzz/fuzz_$t" -max_total_time="$seconds" -runs="$runs" -rss_limit_mb=2048 -timeout=10 \
      -max_len="$max_len" -print_final_stats=1 -artifact_prefix="$findings/" \
      "$corpus" "${seeds[@]}" 2>"$build/fuzz_$t.log"; then
    failed+=("$t")
    tail -40 "$build/fuzz_$t.log" >&2
  fi
  grep -E '^stat::number_of_executed_units|^stat::average_exec_per_sec|^stat::peak_rss_mb' \
    "$build/fuzz_$t.log" | sed "s/^/fuzz: $t: /" >&2 || true
done
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "fuzz: findings in: ${failed[*]} (inputs in $build/findings/<target>/; minimize with" \
       "$build/fuzz/fuzz_<target> -minimize_crash=1 -runs=10000 <input>)" >&2
  exit 1
fi
echo "fuzz: ${#targets[@]} targets ran ${seconds} s each without a finding" >&2
