#!/usr/bin/env bash
# Fuzzes relief: builds the libFuzzer targets of fuzz/ with clang (build-fuzz/),
# runs each for SECONDS (default 180) from a copy of its corpus, and fails if any
# target finds a crash, a sanitizer report, a leak, a hang (> 10 s on one
# input), more than 2 GiB of memory or a single allocation over 1 GiB.
# Findings are left in $OUT (default /tmp/relief-fuzz) as <target>-crash-*,
# -leak-*, -timeout-*, -oom-* files; logs as <target>.log.
# usage: bench/fuzz/run.sh [SECONDS] [TARGET...]   (targets: see fuzz/CMakeLists.txt)
# env:   CXX (default clang++-19), OUT, BUILD_DIR (default build-fuzz)
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-180}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(tile_decode manifest level_index http_request)
out=${OUT:-/tmp/relief-fuzz}
build=${BUILD_DIR:-build-fuzz}
mkdir -p "$out"
# Sanitizer reports with file:line when an llvm-symbolizer is installed.
if [[ -z ${ASAN_SYMBOLIZER_PATH:-} ]] && command -v llvm-symbolizer >/dev/null; then
  export ASAN_SYMBOLIZER_PATH=$(command -v llvm-symbolizer)
fi

cmake -S . -B "$build" -G Ninja -DCMAKE_CXX_COMPILER="${CXX:-clang++-19}" -DRELIEF_FUZZ=ON \
  -DRELIEF_BUILD_TESTS=OFF >/dev/null
nice -n 5 cmake --build "$build" --target fuzz >/dev/null

failed=()
for t in "${targets[@]}"; do
  work="$out/$t-corpus"
  rm -rf "$work" && mkdir -p "$work" && cp fuzz/corpus/"$t"/* "$work"/
  dict=()
  [[ -f fuzz/$t.dict ]] && dict=(-dict=fuzz/$t.dict)
  echo "fuzzing $t for ${seconds}s (log: $out/$t.log)"
  if ! nice -n 19 "$build/fuzz/fuzz_$t" "$work" "${dict[@]}" -max_total_time="$seconds" \
    -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -artifact_prefix="$out/$t-" \
    -print_final_stats=1 >"$out/$t.log" 2>&1; then
    failed+=("$t")
    grep -m1 -E "ERROR|SUMMARY|fuzz property|Timeout|out-of-memory|leak" "$out/$t.log" || true
  fi
  grep -E "stat::number_of_executed_units|stat::new_units_added" "$out/$t.log" | tr '\n' ' '
  echo
done
if ((${#failed[@]})); then
  echo "FINDINGS in: ${failed[*]} (inputs in $out)"
  exit 1
fi
echo "no findings in ${targets[*]} (${seconds}s each)"
