#!/usr/bin/env bash
# Makes the manual's sample report from real runs on this machine: several benchmarks and
# configurations (a --repeat series, two transports, both process layouts, two rates, a grey-box
# run, an INVALID run, control and manipulation) beside the published RobotPerf rows, then its
# screenshot.
#   scripts/report-sample.sh [OUT_DIR]   (default: build/report-sample)
# The DDS runs take a domain no other participant uses (--domain auto).
# Needs a built robotperf (scripts/build.sh; ROBOTPERF=path picks another) and chromium for the
# screenshot.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
robotperf="${ROBOTPERF:-$here/build/robotperf}"
out="${1:-$here/build/report-sample}"
results="$out/results"
published="$here/../shared/data/robotperf"
rm -rf "$results"
mkdir -p "$results"

run() { "$robotperf" run "$@" --quiet --output "$results" > /dev/null; }
# A --repeat series: one configuration, drawn as one bar with its runs as dots.
run a1 --repeat 3
run a1 --rmw fastdds --domain auto
run a1 --processes per-node --domain auto
run a1 --rate 60
run a1 --mode grey
# Fewer samples than the benchmark requires: INVALID (exit status 3), kept in the folder.
run a1 --count 12 || [ $? -eq 3 ]
run a2
run a3
run a4
run a5
run a5 --rmw cyclonedds --domain auto
run c3 --duration 10
run c4 --duration 10
run c5 --duration 10
run d2
run d4
run d6

# The published rows are in the shared reference data, when it is beside the checkout.
if [ -d "$published" ]; then
  "$robotperf" results import "$published/perception" "$published/control" \
    "$published/manipulation" --into "$results" > /dev/null
else
  echo "no published RobotPerf rows at $published: the report shows this machine's runs only" >&2
fi
"$robotperf" report "$results" --title "robotperf sample report" \
  --html "$out/report.html" --md "$out/report.md"

if command -v chromium > /dev/null; then
  chromium --headless --no-sandbox --disable-gpu --no-first-run --hide-scrollbars \
    --user-data-dir="$out/chromium-profile" --window-size=1600,1800 \
    --screenshot="$out/report-sample.png" "file://$out/report.html" 2> /dev/null
  echo "screenshot: $out/report-sample.png (copy it to docs/ to update the manual's)"
fi
echo "report: $out/report.html"
