// The OpenCL devices OpenCV can use, and the one the `opencl` backend of the perception kernels
// runs on.
#pragma once

#include <vector>

#include "robotperf/plugin/kernel.hpp"

namespace robotperf::perception {

// Every OpenCL device of every platform the ICD loader finds (none without an OpenCL driver).
std::vector<plugin::DeviceInfo> opencl_devices();

// The device OpenCV's OpenCL work runs on, chosen once per process: a GPU first, else a CPU or
// accelerator device (OPENCV_OPENCL_DEVICE, when set, chooses instead). Throws
// std::invalid_argument with one line saying what is missing when there is none (with
// OPENCV_OPENCL_DEVICE set, naming it and its value, which then matches no device).
const plugin::DeviceInfo& opencl_device();

}  // namespace robotperf::perception
