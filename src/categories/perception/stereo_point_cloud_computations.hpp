// Private to the perception category: what StereoPointCloudProcessor leaves to its backend, and
// the implementations of it, one per backend in a unit of its own: stereo_point_cloud_cpu.cpp and
// stereo_point_cloud_opencl.cpp. stereo_point_cloud.cpp lists them by backend name.
#pragma once

#include <memory>
#include <opencv2/core.hpp>

#include "robotperf/perception/stereo_point_cloud.hpp"

namespace robotperf::perception {

// What a backend needs to lay out the points: the reprojection matrix, the byte layout of a point
// and where the left image's colours lie in a pixel.
struct StereoCloudModel {
  cv::Matx44d q;
  int point_step = 0;
  bool colour = false;
  int rgb_offset = 0;
  int red = 0, green = 0, blue = 0, colour_bytes = 0;
};

// The points of StereoPointCloudProcessor.
class StereoPointCloudComputation {
 public:
  virtual ~StereoPointCloudComputation() = default;
  // Writes every point of the 32FC1 `disparity` into cloud.data, which is already the cloud's
  // size: x, y, z (NaN where missing), padding zero, and with model.colour the b, g, r, 0 bytes of
  // `left` (8-bit, disparity's size).
  virtual void points(const cv::Mat& disparity, const cv::Mat& left, const StereoCloudModel& model,
                      msgs::PointCloud2& cloud) = 0;
};

// Each throws std::invalid_argument without its backend's device.
std::unique_ptr<StereoPointCloudComputation> make_cpu_stereo_point_cloud();
std::unique_ptr<StereoPointCloudComputation> make_opencl_stereo_point_cloud();

}  // namespace robotperf::perception
