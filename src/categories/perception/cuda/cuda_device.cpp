// The CUDA build's device lookup (cuda_missing.cpp is the other build's).
#include "robotperf/perception/cuda_device.hpp"

#include <cuda_runtime.h>

#include <mutex>
#include <stdexcept>
#include <string>

#include "cuda_check.hpp"

namespace robotperf::perception {
namespace {

// "13.0" from CUDA's 13000.
std::string version_text(int version) {
  return std::to_string(version / 1000) + "." + std::to_string(version % 1000 / 10);
}

plugin::DeviceInfo describe(int device) {
  cudaDeviceProp properties{};
  cuda::check(cudaGetDeviceProperties(&properties, device), "cudaGetDeviceProperties");
  int driver = 0, runtime = 0;
  cuda::check(cudaDriverGetVersion(&driver), "cudaDriverGetVersion");
  cuda::check(cudaRuntimeGetVersion(&runtime), "cudaRuntimeGetVersion");
  return {properties.name, "NVIDIA", "CUDA " + version_text(driver),
          "CUDA " + version_text(runtime), static_cast<uint64_t>(properties.totalGlobalMem)};
}

}  // namespace

bool cuda_backend_built() {
  return true;
}

std::vector<plugin::DeviceInfo> cuda_devices() {
  int count = 0;
  // No driver or no GPU: no devices, which is what this list is for.
  if (cudaGetDeviceCount(&count) != cudaSuccess) return {};
  std::vector<plugin::DeviceInfo> devices;
  for (int d = 0; d < count; ++d) devices.push_back(describe(d));
  return devices;
}

const plugin::DeviceInfo& cuda_device() {
  static std::once_flag once;
  static plugin::DeviceInfo chosen;
  static std::string missing;
  std::call_once(once, [] {
    int count = 0;
    const cudaError_t error = cudaGetDeviceCount(&count);
    if (error != cudaSuccess || count == 0) {
      missing = std::string("the cuda backend found no CUDA device (cudaGetDeviceCount: ") +
                (error != cudaSuccess ? cudaGetErrorString(error) : "0 devices") +
                "): install the NVIDIA driver and check that nvidia-smi lists a GPU (and that "
                "CUDA_VISIBLE_DEVICES, if set, names it)";
      return;
    }
    chosen = describe(0);
  });
  if (!missing.empty()) throw std::invalid_argument(missing);
  return chosen;
}

}  // namespace robotperf::perception
