#!/usr/bin/env bash
# Packs what checking the cuda backend on another machine takes, for a machine with an NVIDIA GPU
# and driver but none of robotperf's Debian packages (a lent cloud GPU, a lab's server): robotperf,
# bench_backends and the cuda tests, the shared libraries they load (all but the C library's, and
# the driver's own, which the GPU machine has), and LTTng's tools for the grey-box split. Run it
# after ./scripts/build.sh on a machine with the CUDA toolkit; it writes .gpu-bundle/bundle.tar.xz
# (git-ignored). Copy the repository with that file to the GPU machine and run
# scripts/gpu-check.sh there, from the repository's root.
# Usage: scripts/gpu-bundle.sh [BUILD_DIR]   (default: build)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-$root/build}" && pwd)
out=$root/.gpu-bundle

die() {
  echo "gpu-bundle: $*" >&2
  exit 1
}

[[ -f "$build/CMakeCache.txt" ]] || die "$build is not a build folder: run ./scripts/build.sh first"
targets=(robotperf bench_backends perception_image_proc_test opencl_device_probe
  perception_stereo_depth_test perception_cuda_disparity_filter_test cli_test)
cmake --build "$build" --target "${targets[@]}" -j "$(nproc)" >/dev/null
[[ "$("$build/robotperf" list kernels)" == *"backends: cpu, opencl, cuda"* ]] ||
  die "$build has no cuda backend: install a CUDA toolkit (scripts/install-deps.sh --cuda) and rebuild"

# The executables, each at its path in the build: the tests name robotperf and the benchmark
# packages by the absolute paths the build gave them, which gpu-check.sh makes again.
# perception_image_proc_test runs opencl_device_probe.
executables=(robotperf bench/backends/bench_backends tests/perception/perception_image_proc_test
  tests/perception/opencl_device_probe tests/perception/perception_stereo_depth_test
  tests/perception/perception_cuda_disparity_filter_test tests/cli/cli_test)
lttng_tools=(/usr/bin/lttng /usr/bin/lttng-sessiond
  /usr/lib/x86_64-linux-gnu/lttng/libexec/lttng-consumerd)
for tool in "${lttng_tools[@]}"; do
  [[ -x "$tool" ]] || die "no $tool: install lttng-tools (scripts/install-deps.sh)"
done

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/build" "$stage/lttng" "$stage/lib/fallback"
for e in "${executables[@]}"; do
  mkdir -p "$stage/build/$(dirname "$e")"
  strip --strip-unneeded -o "$stage/build/$e" "$build/$e"
done
cp "${lttng_tools[@]}" "$stage/lttng/"
# The session daemon validates session files against this schema when it starts.
cp /usr/share/xml/lttng/session.xsd "$stage/lttng/"

# Every library they load, found as this machine's loader finds it. Left out: the C library's
# (the GPU machine's own, as new or newer), and the NVIDIA driver's (it must match the kernel
# module there). libstdc++ and libgcc_s go to fallback/, used only where the machine has none
# new enough. OpenCL's loader is dlopened by OpenCV: taken too, for an OpenCL driver there.
system_library='^(ld-linux-x86-64|libc|libm|libpthread|libdl|librt|libresolv|libutil|libanl)\.so'
# ldd prints "name => path (address)": keep the paths.
mapfile -t libraries < <(
  echo /usr/lib/x86_64-linux-gnu/libOpenCL.so.1
  for e in "${executables[@]}"; do ldd "$build/$e"; done
  for tool in "${lttng_tools[@]}"; do ldd "$tool"; done
)
for line in "${libraries[@]}"; do
  library=$(awk '$2 == "=>" {print $3; next} {print $1}' <<<"$line")
  [[ "$library" == /* ]] || continue
  name=$(basename "$library")
  [[ "$name" =~ $system_library || "$name" == libcuda.so* || "$name" == libnvidia-* ]] && continue
  to=$stage/lib
  [[ "$name" == libstdc++.so* || "$name" == libgcc_s.so* ]] && to=$stage/lib/fallback
  [[ -e "$to/$name" ]] || cp -L "$library" "$to/$name"
done

cat >"$stage/origin" <<EOF
source_dir=$root
build_dir=$build
commit=$(git -C "$root" rev-parse HEAD 2>/dev/null || echo unknown)$(git -C "$root" diff --quiet 2>/dev/null || echo "+changes")
made=$(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -n)
EOF

mkdir -p "$out"
tar -C "$stage" -cJf "$out/bundle.tar.xz.part" .
mv "$out/bundle.tar.xz.part" "$out/bundle.tar.xz"
echo "gpu-bundle: $out/bundle.tar.xz ($(du -h "$out/bundle.tar.xz" | cut -f1)): copy the repository with it to the GPU machine and run scripts/gpu-check.sh there"
