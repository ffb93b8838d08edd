#!/usr/bin/env bash
# Checks the cuda backend on a machine with an NVIDIA GPU and driver, from the bundle that
# scripts/gpu-bundle.sh made (.gpu-bundle/bundle.tar.xz), without building or installing anything:
#   1. the device: nvidia-smi and robotperf sysinfo;
#   2. the cuda kernels against the cpu's on the same inputs (the kernel tests; the speckle
#      filter's 20 times over, as a race between its threads shows only on some runs);
#   3. robotperf run a1 .. a5 --backend cuda, end to end, and a1 device-resident, results kept
#      (results.tar);
#   4. bench_backends: cpu against cuda (and opencl where the machine has a driver for it),
#      p50 / p99, the upload / compute / download split and issue #19's targets;
#   5. the opencl backend on the GPU's own OpenCL driver, where the NVIDIA driver has one: its
#      kernel tests, and a3 (its own OpenCL block matcher) end to end;
#   6. the CLI's cuda test (each benchmark's answers on the GPU, in one process and per node);
#   7. a3 on cpu and cuda in three rounds (bench_backends --repeat 3), its 10x target, at its
#      edge, judged on their medians.
# Three more steps run only when named in GPU_CHECK_STEPS, for whoever speeds the backend up:
#   grey: a1, a3 and a5 on cuda, and a5 on cpu, grey-box (the per-hop breakdown around the
#   kernels);
#   kernel_times: the GPU time of each kernel a3 runs on cuda, by Nsight Compute (ncu).
#   kernel_profile: why a3's matching and region joining kernels take their time (ncu sections).
# GPU_CHECK_STEPS (names separated by spaces) runs only the steps it names.
# Run it from the repository's root. Each step's output goes to a file in OUT_DIR (default $OUT,
# else ./gpu-check), with summary.txt listing each step's outcome, and under a step of several
# commands (the kernel test programs, the benchmarks) each one's: every one runs whether or not
# another failed. The steps share one deadline (GPU_CHECK_SECONDS, default 480) so that the whole
# check ends within a lease's command limit; a step cut short says so in the summary. Exit status:
# 0, 1 when a step did not pass. The unpacked bundle is removed on exit.
set -uo pipefail
root=$(pwd)
bundle=$root/.gpu-bundle
out=${OUT_DIR:-${OUT:-$root/gpu-check}}
deadline=$((SECONDS + ${GPU_CHECK_SECONDS:-480}))
mkdir -p "$out"
summary=$out/summary.txt
: >"$summary"

die() {
  echo "gpu-check: $*" | tee -a "$summary" >&2
  exit 1
}

[[ -f "$bundle/bundle.tar.xz" ]] ||
  die "no $bundle/bundle.tar.xz: run scripts/gpu-bundle.sh on the build machine and copy it here"
unpacked=$(mktemp -d /tmp/robotperf-gpu.XXXXXX) || die "cannot make a folder in /tmp"
links=()  # the links made here to the bundle's paths, removed with it
cleanup() {
  local link
  for link in ${links[@]+"${links[@]}"}; do
    [[ -L "$link" ]] && rm -f "$link"
  done
  rm -rf "$unpacked"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
# Python's tarfile where there is no xz program.
if command -v xz >/dev/null; then
  tar -C "$unpacked" -xJf "$bundle/bundle.tar.xz" || die "cannot unpack the bundle"
else
  python3 -m tarfile -e "$bundle/bundle.tar.xz" "$unpacked" || die "cannot unpack the bundle"
fi
cat "$unpacked/origin" >>"$summary"
source_dir=$(sed -n 's/^source_dir=//p' "$unpacked/origin")
build_dir=$(sed -n 's/^build_dir=//p' "$unpacked/origin")

# The paths the build gave the sources and executables, which the tests use: made again here.
if [[ "$source_dir" != "$root" ]]; then
  if [[ -e "$source_dir" && ! "$source_dir" -ef "$root" ]]; then
    die "$source_dir (where the bundle was built) exists here and is not this repository"
  fi
  mkdir -p "$(dirname "$source_dir")"
  if [[ ! -e "$source_dir" ]]; then
    ln -s "$root" "$source_dir" && links+=("$source_dir")
  fi
fi
if [[ -e "$build_dir" && ! -L "$build_dir" ]]; then
  die "$build_dir (the bundle's build folder) exists here: remove it or check from another copy"
fi
rm -f "$build_dir"
ln -s "$unpacked/build" "$build_dir" && links+=("$build_dir")

export LD_LIBRARY_PATH=$unpacked/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
# The build machine's libstdc++ only where this machine's cannot run robotperf.
if ! "$build_dir/robotperf" --version >/dev/null 2>&1; then
  export LD_LIBRARY_PATH=$LD_LIBRARY_PATH:$unpacked/lib/fallback
fi
"$build_dir/robotperf" --version >>"$summary" 2>&1 ||
  die "robotperf does not start here (is the C library older than the build machine's?): $("$build_dir/robotperf" --version 2>&1 | head -1)"
export PATH=$unpacked/lttng:$PATH
export LTTNG_CONSUMERD64_BIN=$unpacked/lttng/lttng-consumerd
export LTTNG_CONSUMERD64_LIBDIR=$unpacked/lib
export LTTNG_SESSION_CONFIG_XSD_PATH=$unpacked/lttng
# An OpenCL driver for the GPU, where the NVIDIA driver has one: the opencl backend's column.
if [[ -z "${OCL_ICD_VENDORS:-}" ]]; then
  opencl=$(ldconfig -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1/ {print $NF; exit}')
  [[ -n "$opencl" ]] || opencl=$(find /usr/local/nvidia /usr/lib /usr/lib64 -name 'libnvidia-opencl.so.1' 2>/dev/null | head -1)
  if [[ -n "$opencl" ]]; then
    mkdir -p "$unpacked/icd"
    echo "$opencl" >"$unpacked/icd/nvidia.icd"
    export OCL_ICD_VENDORS=$unpacked/icd
  fi
fi

# each LABEL COMMAND [LABEL COMMAND]...: runs every COMMAND (a bash command line), whatever the
# others' exit status, saying "each: LABEL: passed" or "each: LABEL: exit N" after it; fails when
# one failed. A step runs it as "${each[@]}" LABEL COMMAND ...
each() {
  local failed=0 rc
  while (($# >= 2)); do
    echo "=== $1: $2"
    bash -c "$2"
    rc=$?
    if ((rc == 0)); then
      echo "each: $1: passed"
    else
      echo "each: $1: exit $rc"
      failed=1
    fi
    shift 2
  done
  return "$failed"
}
export -f each
# shellcheck disable=SC2016 # expanded by the inner shell
each=(bash -c 'each "$@"' each)

failures=0
# step NAME LIMIT_SECONDS COMMAND...: runs it into OUT_DIR/NAME.txt within the shared deadline.
step() {
  local name=$1 limit=$2
  shift 2
  if [[ -n "${GPU_CHECK_STEPS:-}" && " $GPU_CHECK_STEPS " != *" $name "* ]] ||
    [[ -z "${GPU_CHECK_STEPS:-}" && "$name" =~ ^(grey|kernel_times|kernel_profile)$ ]]; then
    return
  fi
  local left=$((deadline - SECONDS))
  if ((left < 10)); then
    echo "$name: not run (the deadline was reached)" | tee -a "$summary"
    failures=$((failures + 1))
    return
  fi
  ((limit > left)) && limit=$left
  local start=$SECONDS
  timeout --kill-after=10 "$limit" "$@" >"$out/$name.txt" 2>&1
  local rc=$?
  local outcome="exit $rc"
  ((rc == 0)) && outcome=passed
  ((rc == 124 || rc == 137)) && outcome="cut short after ${limit} s"
  # A test that skips here (no device, no driver) checked nothing: say so.
  local skipped
  skipped=$(grep -c '^\[  SKIPPED \] .* ms)$' "$out/$name.txt")
  ((skipped > 0)) && outcome="$outcome, $skipped tests SKIPPED"
  echo "$name: $outcome ($((SECONDS - start)) s)" | tee -a "$summary"
  # Each command of the step (each above), as far as it got.
  sed -n 's/^each: /  /p' "$out/$name.txt" | tee -a "$summary"
  ((rc == 0)) || failures=$((failures + 1))
}

cd "$build_dir" || die "cannot enter $build_dir"
step device 60 bash -c 'nvidia-smi && ./robotperf sysinfo'
step kernels 120 "${each[@]}" \
  image_proc "./tests/perception/perception_image_proc_test --gtest_filter='*Cuda*'" \
  stereo_depth "./tests/perception/perception_stereo_depth_test --gtest_filter='*Cuda*'" \
  cuda_disparity_filter "./tests/perception/perception_cuda_disparity_filter_test --gtest_repeat=20"
results=$(printf %q "$out/results")
runs=()
for b in a1 a2 a3 a4 a5; do
  runs+=("$b" "./robotperf run $b --backend cuda --output $results")
done
runs+=("a1 device-resident" "./robotperf run a1 --backend cuda --device-resident --output $results")
step runs 150 "${each[@]}" "${runs[@]}"
step opencl_kernels 45 "${each[@]}" \
  image_proc "./tests/perception/perception_image_proc_test --gtest_filter='*OpenCl*'" \
  stereo_depth "./tests/perception/perception_stereo_depth_test --gtest_filter='*OpenCl*'"
step opencl_a3 60 ./robotperf run a3 --backend opencl --connect-timeout 45 --output "$out/results"
step bench_backends 300 ./bench/backends/bench_backends
step cli 200 ./tests/cli/cli_test --gtest_filter='*Cuda*'
# a3's 10x target is at its edge: judged on three rounds of cpu and cuda runs.
step a3_rounds 150 ./bench/backends/bench_backends --backends cuda --repeat 3 a3
step grey 60 "${each[@]}" \
  "a1 cuda" "./robotperf run a1 --backend cuda --mode grey --count 150 --output $results" \
  "a5 cuda" "./robotperf run a5 --backend cuda --mode grey --count 150 --output $results" \
  "a5 cpu" "./robotperf run a5 --mode grey --count 150 --output $results" \
  "a3 cuda" "./robotperf run a3 --backend cuda --mode grey --count 150 --output $results"
# One metric, one pass per kernel; past the warm-up (a3 launches 12 kernels a message). ncu with
# its own libraries, not the bundle's. Profiled, the graph falls behind its rate: the run is
# invalid (exit status 3), the kernels' times are what this step is for.
# shellcheck disable=SC2016 # expanded by the inner shell
step kernel_times 80 env -u LD_LIBRARY_PATH PATH="$PATH:/usr/local/cuda/bin" \
  LIBRARIES="$LD_LIBRARY_PATH" bash -c 'ncu --metrics gpu__time_duration.sum --launch-skip 240 \
  --launch-count 36 env LD_LIBRARY_PATH="$LIBRARIES" ./robotperf run a3 --backend cuda --count 40 \
  --connect-timeout 60 --output /tmp/robotperf-ncu; status=$?; ((status == 0 || status == 3))'
# Why a3's two slowest kernels take their time: Nsight Compute's throughput, launch, occupancy
# and warp-stall sections, two launches of each (several replays a launch).
# shellcheck disable=SC2016 # expanded by the inner shell
step kernel_profile 120 env -u LD_LIBRARY_PATH PATH="$PATH:/usr/local/cuda/bin" \
  LIBRARIES="$LD_LIBRARY_PATH" bash -c 'ncu --kernel-name regex:"match_kernel|join_regions_kernel" \
  --section SpeedOfLight --section LaunchStats --section Occupancy --section WarpStateStats \
  --section SchedulerStats --launch-skip 40 --launch-count 4 \
  env LD_LIBRARY_PATH="$LIBRARIES" ./robotperf run a3 --backend cuda --count 40 \
  --connect-timeout 60 --output /tmp/robotperf-ncu; status=$?; ((status == 0 || status == 3))'
# The results as one file: a lent machine hands back few files.
if [[ -d "$out/results" ]]; then
  tar -C "$out" -cf "$out/results.tar" results && rm -rf "$out/results"
fi
echo "gpu-check: outputs in $out; $failures steps did not pass" | tee -a "$summary"
((failures == 0))
