#!/usr/bin/env bash
# The example plug-in as a user builds it: install robotperf into a fresh prefix, build
# examples/plugin against the installed package (find_package(robotperf)), load it with
# --plugin into the installed robotperf and run its benchmark end to end, functional check
# included. Usage: example_plugin_test.sh <robotperf build dir> <source dir> <domain, or auto>
set -euo pipefail
build=$1 source=$2 domain=$3
work=$(mktemp -d "${TMPDIR:-/tmp}/robotperf-example-plugin-XXXXXX")
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$work/prefix" >/dev/null
robotperf=$work/prefix/bin/robotperf
[[ -x $robotperf ]] || fail "no robotperf installed"
[[ -f $work/prefix/include/robotperf/plugin.hpp ]] || fail "no plug-in headers installed"

# Built against the installed package only: nothing of the source tree on its include path.
cmake -S "$source/examples/plugin" -B "$work/plugin" -DCMAKE_PREFIX_PATH="$work/prefix" \
  >"$work/configure.log" 2>&1 || { cat "$work/configure.log"; fail "configure"; }
cmake --build "$work/plugin" >"$work/build.log" 2>&1 || { cat "$work/build.log"; fail "build"; }
plugin=$work/plugin/librobotperf_canny_edges.so
[[ -f $plugin ]] || fail "no plug-in built"

# The installed robotperf finds its own benchmark packages, the example's are added to them.
kernels=$("$robotperf" --plugin "$plugin" list kernels)
grep -qF "example/canny  (from $plugin; backends: cpu, opencl)" <<<"$kernels" \
  || fail "list kernels does not show the plug-in's kernel"
evaluators=$("$robotperf" --plugin "$plugin" list evaluators)
grep -q "^example/canny_edges" <<<"$evaluators" || fail "list evaluators does not show the plug-in's evaluator"
listed=$("$robotperf" --benchmarks "$source/examples/plugin/benchmarks" --plugin "$plugin" list)
grep -q "^a1 " <<<"$listed" || fail "installed built-in benchmarks not found"
grep -q "^e1 " <<<"$listed" || fail "example benchmark not found"

"$robotperf" --plugin "$plugin" --benchmarks "$source/examples/plugin/benchmarks" run e1 \
  --quiet --domain "$domain" --output "$work/results" >"$work/run.log" 2>&1 \
  || { cat "$work/run.log"; fail "run e1 did not give a valid result"; }
result=$(ls "$work"/results/e1-*.json)
grep -q '"evaluator": "example/canny_edges"' "$result" || fail "no functional section"
grep -q '"pixel_agreement"' "$result" || fail "no pixel_agreement metric"
grep -q "functional result: VALID" "$work/run.log" || { cat "$work/run.log"; fail "functional verdict not printed"; }

# The second backend: it runs where OpenCV has an OpenCL device, else says what is missing.
mkdir -p "$work/bench/example"
cp -r "$source/examples/plugin/benchmarks/example/e1_canny_edges" "$work/bench/example/e2_canny_opencl"
sed -i 's/^id: e1/id: e2/; s/^name: e1_canny_edges/name: e2_canny_opencl/' "$work/bench/example/e2_canny_opencl/benchmark.yaml"
sed -i 's/backend: cpu/backend: opencl/' "$work/bench/example/e2_canny_opencl/graph.yaml"
set +e
"$robotperf" --plugin "$plugin" --benchmarks "$work/bench" run e2 --quiet --domain "$domain" \
  --output "$work/results2" >"$work/run2.log" 2>&1
code=$?
set -e
if [[ $code -eq 2 ]]; then
  grep -q "backend opencl needs an OpenCL device" "$work/run2.log" || { cat "$work/run2.log"; fail "opencl refusal unclear"; }
  [[ $(wc -l <"$work/run2.log") -eq 1 ]] || { cat "$work/run2.log"; fail "opencl refusal is not one line"; }
elif [[ $code -ne 0 ]]; then
  cat "$work/run2.log"; fail "opencl backend: exit $code"
fi
echo "example plug-in: built against the installed robotperf, e1 valid; opencl backend exit $code"
