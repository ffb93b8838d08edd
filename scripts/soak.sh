#!/usr/bin/env bash
# Soak test (not run by CI): one long run of a benchmark over Fast DDS with a process per node,
# sampling the resident memory of robotperf and of every node process while it runs.
#
#   scripts/soak.sh [seconds, default 3600] [benchmark, default a1]
#   scripts/soak.sh --analyse DIR    # judges a finished soak again from its folder
#
# Environment: ROBOTPERF (the executable, default build/robotperf), SOAK_DOMAIN (DDS domain,
# default 213), SOAK_DIR (where the result and memory samples go, default a new temporary
# folder), SOAK_MAX_GROWTH_MIB (allowed RSS growth of any process over the second half of the run,
# default 4).
#
# Passes (exit 0) when the run completed and is valid with 0 lost, 0 unknown and 0 duplicate
# messages, and no process's memory grew by more than the allowance. Prints the figures either way.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
max_growth_kib=$((${SOAK_MAX_GROWTH_MIB:-4} * 1024))
analyse_only=0
if [ "${1:-}" = --analyse ]; then
  analyse_only=1
  dir=${2:?"soak.sh --analyse needs the soak's folder"}
  # The run's length, as sampled.
  seconds=$(awk -F, 'NR > 1 && $1 > m { m = $1 } END { print m + 0 }' "$dir/memory.csv")
  status=0
else
  seconds=${1:-3600}
  benchmark=${2:-a1}
  dir=${SOAK_DIR:-$(mktemp -d "${TMPDIR:-/tmp}/robotperf-soak.XXXXXX")}
fi
robotperf=${ROBOTPERF:-$root/build/robotperf}
domain=${SOAK_DOMAIN:-213}
samples="$dir/memory.csv"
period=$((seconds / 360 > 10 ? 10 : (seconds / 360 < 1 ? 1 : seconds / 360)))

if [ "$analyse_only" = 0 ]; then
  [ -x "$robotperf" ] || {
    echo "soak.sh: $robotperf not found; build first (scripts/build.sh) or set ROBOTPERF" >&2
    exit 2
  }
  mkdir -p "$dir/results"
  echo "elapsed_s,pid,name,rss_kib" >"$samples"

  "$robotperf" run "$benchmark" --rmw fastdds --processes per-node --duration "$seconds" \
    --domain "$domain" --output "$dir/results" --quiet >"$dir/run.log" 2>&1 &
  run_pid=$!
  trap 'kill -INT "$run_pid" 2>/dev/null || true' INT TERM
  # Should this script end early, the run ends with it.
  trap 'kill -INT "$run_pid" 2>/dev/null || true' EXIT

  # The run and every process below it (node processes run in their own process groups, but stay
  # robotperf's children).
  descendants() {
    local pid=$1 child
    echo "$pid"
    # The children files hold pids separated by spaces: split on words.
    # shellcheck disable=SC2013
    for child in $(cat /proc/"$pid"/task/*/children 2>/dev/null); do descendants "$child"; done
  }

  start=$(date +%s)
  echo "soak: $benchmark for ${seconds}s over fastdds, per-node, domain $domain; samples in $samples"
  while kill -0 "$run_pid" 2>/dev/null; do
    now=$(($(date +%s) - start))
    for pid in $(descendants "$run_pid"); do
      rss=$(awk '/^VmRSS:/ {print $2}' /proc/"$pid"/status 2>/dev/null) || continue
      [ -n "$rss" ] || continue
      # The process may end between the two reads: it is skipped then.
      name=$({ tr '\0' ' ' </proc/"$pid"/cmdline; } 2>/dev/null | awk '{
        for (i = 1; i <= NF; ++i) if ($i == "--node") { print "node:" $(i + 1); exit }
        print "robotperf" }') || continue
      echo "$now,$pid,$name,$rss" >>"$samples"
    done
    sleep "$period" &
    wait $! || true
  done
  status=0
  wait "$run_pid" || status=$?
  trap - EXIT
  cat "$dir/run.log"
  [ "$status" -eq 0 ] || echo "soak: robotperf exited $status"
fi

result=$(find "$dir/results" -maxdepth 1 -name '*.json' 2>/dev/null | sort | head -n 1)
[ -n "$result" ] || {
  echo "soak: FAILED, no result written"
  exit 1
}

# Memory: per process, the largest RSS around the middle of the run (45-50 %) against the largest
# in its last tenth. A leak grows all the time and shows there; a step taken once while the machine
# was loaded (queues filling, then glibc keeping the pages) is a high-water mark, not a leak: the
# growth since the first tenth is printed too, so that such a step is visible.
memory_ok=1
if ! awk -F, -v total="$seconds" -v limit="$max_growth_kib" 'NR > 1 {
    name[$2] = $3
    if ($1 >= total * 0.05 && $1 <= total * 0.1 && $4 > early[$2]) early[$2] = $4
    if ($1 >= total * 0.45 && $1 <= total * 0.5 && $4 > middle[$2]) middle[$2] = $4
    if ($1 >= total * 0.9 && $4 > late[$2]) late[$2] = $4
  }
  END {
    bad = 0
    for (p in name) {
      if (!(p in early) || !(p in middle) || !(p in late)) continue
      growth = late[p] - middle[p]
      printf "memory: %-20s pid %-7s %7.1f MiB (first tenth) %7.1f MiB (middle) %7.1f MiB (end): %+.1f MiB over the second half\n",
             name[p], p, early[p] / 1024, middle[p] / 1024, late[p] / 1024, growth / 1024
      if (growth > limit) bad = 1
    }
    exit bad
  }' "$samples"; then
  memory_ok=0
fi

# The result: complete, valid, nothing lost, unknown or duplicated.
flat=$(tr -d ' \n' <"$result")
section() { echo "$flat" | grep -o "\"$1\":{[^}]*}" | head -n 1; }
field() { echo "$1" | grep -o "\"$2\":[^,}]*" | head -n 1 | cut -d: -f2; }
counts=$(section counts)
latency=$(section from_scheduled)
echo "result: $result"
echo "counts: sent $(field "$counts" sent), measured $(field "$counts" measured)," \
  "matched $(field "$counts" matched), lost $(field "$counts" lost)," \
  "unknown $(field "$counts" unknown), duplicates $(field "$counts" duplicates)"
echo "latency_ms: p50 $(field "$latency" p50), p99 $(field "$latency" p99)," \
  "p99.9 $(field "$latency" p999), max $(field "$latency" max)"

ok=1
[[ $flat == *'"completed":true'* && $flat == *'"interrupted":false'* ]] || ok=0
[ "$(field "$(section validity)" valid)" = true ] || ok=0
[ "$(field "$counts" lost)" = 0 ] && [ "$(field "$counts" unknown)" = 0 ] &&
  [ "$(field "$counts" duplicates)" = 0 ] || ok=0
if [ "$ok" = 1 ] && [ "$memory_ok" = 1 ] && [ "$status" -eq 0 ]; then
  echo "soak: PASSED"
else
  echo "soak: FAILED"
  exit 1
fi
