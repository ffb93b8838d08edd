#!/usr/bin/env bash
# Installs dependencies (if missing), configures and builds robotperf into ./build.
# Extra arguments are passed to the CMake configure step (e.g. -DROBOTPERF_CUDA=OFF), for this
# build only.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
# CMake looks for nvcc on PATH only: point it at NVIDIA's default install when nvcc is there
# and nothing else names a CUDA compiler. Without any toolkit the cuda backend is left out.
cuda_compiler=()
if ! command -v nvcc >/dev/null && [[ -x /usr/local/cuda/bin/nvcc && -z "${CUDACXX:-}" ]] &&
  [[ " $* " != *" -DCMAKE_CUDA_COMPILER="* && " $* " != *" -DROBOTPERF_CUDA=OFF "* ]]; then
  cuda_compiler=(-DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc)
fi
# The defaults of every option are given each time, before the extra arguments: an option given
# once (a sanitized build, one GPU architecture, no tests) does not stay in ./build's cache for
# every later plain build.
mkdir -p "$root/build"
log="$root/build/configure.log"
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DROBOTPERF_SANITIZE=OFF \
  -DROBOTPERF_CUDA=ON -DROBOTPERF_BUILD_TESTS=ON -DROBOTPERF_BUILD_BENCH=ON -DROBOTPERF_FUZZ=OFF \
  -UCMAKE_CUDA_ARCHITECTURES "${cuda_compiler[@]}" "$@" >"$log" || {
  cat "$log"
  exit 1
}
# What was built, as configured (the cuda backend, a sanitized build).
grep '^-- robotperf:' "$log" || true
cmake --build "$root/build" -j "$(nproc)"
