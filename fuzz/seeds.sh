#!/usr/bin/env bash
# Fills a corpus folder with seed inputs for one fuzz target, from the repo's own files (benchmark
# packages, fuzz/seeds/<target>/) and the shared reference data (real rosbag2 bags, .msg files,
# published RobotPerf benchmark.yaml files) when it is there:
#   fuzz/seeds.sh <target> <corpus folder>
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
target=$1
corpus=$2
data=${ROBOTPERF_SHARED_DATA:-$root/../shared/data}
mkdir -p "$corpus"

[ -d "$root/fuzz/seeds/$target" ] && cp "$root/fuzz/seeds/$target"/* "$corpus/"
case $target in
  fuzz_mcap_reader) find "$data/rosbag2" -name '*.mcap' -exec cp {} "$corpus/" \; 2>/dev/null || true ;;
  fuzz_sqlite_reader) find "$data/rosbag2" -name '*.db3' -exec cp {} "$corpus/" \; 2>/dev/null || true ;;
  fuzz_msg_parser)
    find "$data/msg" -name '*.msg' -size -8k -exec cp {} "$corpus/" \; 2>/dev/null || true
    ;;
  fuzz_benchmark_packages)
    # The target's input: benchmark.yaml, a "---8<---" line, graph.yaml.
    for graph in "$root"/benchmarks/*/*/graph.yaml; do
      package=$(dirname "$graph")
      { cat "$package/benchmark.yaml" && printf '\n---8<---\n' && cat "$graph"; } \
        >"$corpus/$(basename "$package").yaml"
    done
    # Ids and names that would leave the output folder, for the fuzzer to vary.
    a1="$root/benchmarks/perception/a1_perception_2nodes"
    if [ -f "$a1/graph.yaml" ]; then
      n=0
      for id in '../../ESCAPED' '/abs/ABSOLUTE' '""' '"a\nb"' '.hidden' '-dash'; do
        n=$((n + 1))
        { sed "s|^id: .*|id: $id|" "$a1/benchmark.yaml" && printf '\n---8<---\n' &&
          cat "$a1/graph.yaml"; } >"$corpus/escaping-id-$n.yaml"
      done
      { cat "$a1/benchmark.yaml" && printf '\n---8<---\n' &&
        sed 's|^nodes:|launch:\n  - {name: ../../x, command: [true]}\nnodes:|' "$a1/graph.yaml"; } \
        >"$corpus/escaping-launch-name.yaml"
    fi
    if [ -d "$data/robotperf" ]; then
      find "$data/robotperf" -name benchmark.yaml | while read -r published; do
        cp "$published" "$corpus/published-$(basename "$(dirname "$published")").yaml"
      done
    fi
    ;;
esac
