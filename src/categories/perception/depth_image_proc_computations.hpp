// Private to the perception category: what PointCloudXyzrgbProcessor leaves to its backend, and
// the implementations of it, one per backend in a unit of its own: depth_image_proc_cpu.cpp,
// depth_image_proc_opencl.cpp and cuda/cuda_depth_image_proc.cpp. depth_image_proc.cpp lists them
// by backend name.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>

#include "robotperf/perception/depth_image_proc.hpp"
#include "xyzrgb_model.hpp"

namespace robotperf::perception {

// Depth in the image's own unit: metres for float, millimetres for uint16.
template <class T>
struct DepthTraits;
template <>
struct DepthTraits<float> {
  static bool valid(float d) { return std::isfinite(d); }
  static float to_metres(float d) { return d; }
  static float from_metres(double m) { return static_cast<float>(m); }
};
template <>
struct DepthTraits<uint16_t> {
  static bool valid(uint16_t d) { return d != 0; }
  static float to_metres(uint16_t d) { return d * 0.001f; }
  // Rounded to the nearest millimetre in float, as depth_image_proc's fromMeters (2.01 m is 2010,
  // not 2009); a range beyond the encoding's 65.535 m saturates instead of wrapping.
  static uint16_t from_metres(double m) {
    return static_cast<uint16_t>(std::min(static_cast<float>(m) * 1000.0f + 0.5f, 65535.0f));
  }
};

// The points of PointCloudXyzrgbProcessor.
class PointCloudComputation {
 public:
  virtual ~PointCloudComputation() = default;
  // Writes the points of `depth` (32FC1 or 16UC1, as model.metres), coloured by the 8-bit
  // `colour` (resized to depth's size, bilinear, where it differs), into cloud.data, which is
  // already the cloud's size: every point's x, y, z and b, g, r bytes.
  virtual void xyzrgb(const cv::Mat& depth, const cv::Mat& colour, const XyzrgbModel& model,
                      msgs::PointCloud2& cloud) = 0;
};

// Each throws std::invalid_argument without its backend's device.
std::unique_ptr<PointCloudComputation> make_cpu_point_cloud();
std::unique_ptr<PointCloudComputation> make_opencl_point_cloud();
std::unique_ptr<PointCloudComputation> make_cuda_point_cloud();

}  // namespace robotperf::perception
