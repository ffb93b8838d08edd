// The CUDA devices, and the one the `cuda` backend of the perception kernels runs on.
#pragma once

#include <vector>

#include "robotperf/plugin/kernel.hpp"

namespace robotperf::perception {

// Why the perception kernels have no cuda backend in a robotperf built without the CUDA toolkit.
inline constexpr const char* kCudaNotBuilt =
    "the cuda backend was not built into this robotperf: install the CUDA toolkit "
    "(scripts/install-deps.sh --cuda, Debian's nvidia-cuda-toolkit from non-free, or NVIDIA's) "
    "and rebuild";

// Whether this robotperf was built with the CUDA toolkit (CMake found nvcc and ROBOTPERF_CUDA was
// not OFF): only then do the perception kernels have a cuda backend.
bool cuda_backend_built();

// Every CUDA device the runtime sees (CUDA_VISIBLE_DEVICES applies): none without a CUDA build,
// an NVIDIA driver or a GPU.
std::vector<plugin::DeviceInfo> cuda_devices();

// The device the cuda backend runs on: the runtime's device 0 (CUDA_VISIBLE_DEVICES chooses which
// GPU that is), looked up once per process. Throws std::invalid_argument with one line saying
// what is missing: a CUDA build (kCudaNotBuilt), or a device and its driver (naming CUDA's
// error).
const plugin::DeviceInfo& cuda_device();

}  // namespace robotperf::perception
