// Private to the cuda backend: every CUDA runtime call's result checked the same way.
#pragma once

#include <cuda_runtime.h>

#include <stdexcept>
#include <string>

namespace robotperf::perception::cuda {

// Throws std::runtime_error naming `call` and CUDA's description of `error`, unless it is
// cudaSuccess.
inline void check(cudaError_t error, const char* call) {
  if (error != cudaSuccess) {
    throw std::runtime_error(std::string("cuda: ") + call + ": " + cudaGetErrorString(error));
  }
}

// After a kernel launch: whether it was launched (its configuration, the device's state).
inline void check_launch(const char* kernel) {
  check(cudaGetLastError(), kernel);
}

}  // namespace robotperf::perception::cuda
