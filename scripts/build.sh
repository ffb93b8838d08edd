#!/usr/bin/env bash
# Installs dependencies (if missing), configures and builds robotperf into ./build.
# Extra arguments are passed to the CMake configure step (e.g. -DROBOTPERF_CUDA=OFF).
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
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release "${cuda_compiler[@]}" "$@" >/dev/null
cmake --build "$root/build" -j "$(nproc)"
