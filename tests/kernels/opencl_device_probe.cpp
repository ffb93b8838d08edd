// The opencl backend's device as a process of its own sees it (OpenCV chooses its OpenCL device
// once per process, from the environment): prints the device's name, or the one line saying why
// there is none and exits 2.
#include <iostream>
#include <stdexcept>

#include "robotperf/perception/opencl_device.hpp"

int main() {
  try {
    std::cout << robotperf::perception::opencl_device().name << "\n";
    return 0;
  } catch (const std::invalid_argument& e) {
    std::cout << e.what() << "\n";
    return 2;
  }
}
