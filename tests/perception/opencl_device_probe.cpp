// The opencl backend's device as a process of its own sees it (OpenCV chooses its OpenCL device
// once per process, from the environment). With no argument it asks for the device and prints
// its name; with one (rectifier, resizer, disparity or point_cloud) it builds that kernel on the
// opencl backend, as a plug-in would without a node, and prints "built". Where there is no
// device, it prints the one line saying why and exits 2.
#include <iostream>
#include <stdexcept>
#include <string>

#include "robotperf/perception/depth_image_proc.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "robotperf/perception/stereo_image_proc.hpp"

namespace perception = robotperf::perception;

int main(int argc, char** argv) {
  const std::string kernel = argc > 1 ? argv[1] : "";
  constexpr const char* kOpenCl = "opencl";
  try {
    if (kernel.empty()) {
      std::cout << perception::opencl_device().name << "\n";
      return 0;
    }
    if (kernel == "rectifier") {
      perception::Rectifier rectifier(cv::INTER_LINEAR, kOpenCl);
    } else if (kernel == "resizer") {
      perception::Resizer resizer(perception::ResizeParams{}, kOpenCl);
    } else if (kernel == "disparity") {
      perception::DisparityProcessor disparity(perception::StereoParams{}, kOpenCl);
    } else if (kernel == "point_cloud") {
      perception::PointCloudXyzrgbProcessor point_cloud(kOpenCl);
    } else {
      std::cout << "unknown kernel '" << kernel << "'\n";
      return 1;
    }
    std::cout << "built\n";
    return 0;
  } catch (const std::invalid_argument& e) {
    std::cout << e.what() << "\n";
    return 2;
  }
}
