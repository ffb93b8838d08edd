// The kernel tests' view of the cuda backend: whether this machine can run it, and what asking for
// it says where it cannot.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <stdexcept>
#include <string>

#include "robotperf/perception/cuda_device.hpp"

namespace robotperf::perception {

// The reason to skip a test that needs a CUDA device (this robotperf built without CUDA, or no
// device or driver), else empty.
inline std::string without_cuda() {
  try {
    cuda_device();
    return "";
  } catch (const std::invalid_argument& e) {
    return std::string("no CUDA device: ") + e.what();
  }
}

// `make` builds something on the cuda backend where there is none: it throws
// std::invalid_argument with one line saying what is missing (the build, or a device).
inline void expect_cuda_missing_line(const std::function<void()>& make, const char* what) {
  try {
    make();
    ADD_FAILURE() << what << " was built without a CUDA device";
  } catch (const std::invalid_argument& e) {
    const std::string line = e.what();
    EXPECT_EQ(line.find('\n'), std::string::npos) << what << ": " << line;
    const char* names = cuda_backend_built() ? "no CUDA device" : "install-deps.sh --cuda";
    EXPECT_NE(line.find(names), std::string::npos) << what << ": " << line;
  }
}

}  // namespace robotperf::perception
