#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (into ./build-fuzz) and runs each for
# a bounded time: scripts/fuzz.sh [seconds per target, default 60] [target...]
# FUZZ_RUNS=N stops a target after N executions instead, if that comes first.
# Needs clang-14 and libclang-rt-14-dev (Debian). Crashing inputs are kept in
# build-fuzz/findings/<target>/; the corpora grow in build-fuzz/corpus/<target>/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_mcap_reader fuzz_sqlite_reader fuzz_cdr_typed fuzz_cdr_dynamic
  fuzz_msg_parser fuzz_benchmark_packages fuzz_results_json fuzz_ctf_trace)
build="$root/build-fuzz"

for tool in clang-14 clang++-14; do
  command -v "$tool" >/dev/null || {
    echo "fuzz.sh: $tool not found; install clang-14 and libclang-rt-14-dev" >&2
    exit 2
  }
done

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 -DROBOTPERF_FUZZ=ON \
  -DROBOTPERF_BUILD_TESTS=OFF -DROBOTPERF_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${targets[@]}"

status=0
for target in "${targets[@]}"; do
  corpus="$build/corpus/$target"
  findings="$build/findings/$target"
  mkdir -p "$corpus" "$findings"
  [ -n "$(ls -A "$corpus")" ] || "$root/fuzz/seeds.sh" "$target" "$corpus"
  echo "== $target for ${seconds}s"
  if ! "$build/fuzz/$target" "$corpus" -max_total_time="$seconds" -runs="${FUZZ_RUNS:--1}" -timeout=10 -rss_limit_mb=2048 \
      -max_len=65536 -artifact_prefix="$findings/" -print_final_stats=1 2>"$build/$target.log"; then
    echo "$target FAILED: see $build/$target.log and $findings/" >&2
    tail -n 30 "$build/$target.log" >&2
    status=1
  else
    grep -E 'stat::number_of_executed_units|cov:' "$build/$target.log" | tail -n 2
  fi
done
exit $status
