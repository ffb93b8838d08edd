// The CUDA devices, and the one the `cuda` backend of the perception kernels runs on.
#pragma once

#include <cstddef>
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

// The floor under the cuda backend's upload and download stages: what moving `bytes` to the
// device and back takes on this machine with no kernel, each way timed to the end of its wait.
// Medians in microseconds.
struct CudaTransferFloor {
  std::size_t bytes = 0;
  int repetitions = 0;
  // The DMA alone: one copy between page-locked host memory and the device.
  double pinned_upload_us = 0, pinned_download_us = 0;
  // The backend's own way (every message pays it): the image copied into page-locked memory, then
  // the DMA; back, the DMA, then the copy out of page-locked memory into the output.
  double staged_upload_us = 0, staged_download_us = 0;
  // A copy straight from and to ordinary (pageable) memory, which the driver stages itself.
  double pageable_upload_us = 0, pageable_download_us = 0;
};

// Times the three ways in turn, `repetitions` times, on a stream of its own, with the host's bytes
// warm in its caches (a floor: a message's bytes may be colder). Checks that the bytes come back
// as they went (std::runtime_error if not); throws as cuda_device() does without a device.
CudaTransferFloor cuda_transfer_floor(std::size_t bytes, int repetitions);

}  // namespace robotperf::perception
