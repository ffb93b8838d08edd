#pragma once

// Disparity image to point cloud as ROS 2 stereo_image_proc's PointCloudNode computes it, through
// image_geometry's StereoCameraModel and OpenCV's reprojectImageTo3D, without the node plumbing.

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/perception/image_proc.hpp"

namespace robotperf::perception {

// PointCloudNode's parameters, with its defaults.
struct StereoPointCloudParams {
  bool use_color = true;                   // an "rgb" field from the left image
  bool avoid_point_cloud_padding = false;  // fields back to back, no alignment padding
};

// The z image_geometry gives a pixel without a disparity (StereoCameraModel::MISSING_Z).
inline constexpr float kMissingZ = 10000.0f;

// Builds the organised cloud (height x width of the disparity image) of a left image, the pair's
// CameraInfos and their 32FC1 disparity, as PointCloudNode does:
// - Q is image_geometry's (ROS 2): with Tx = -baseline = right P[3] / right P[0] and the left
//   camera's fx, fy, cx, cy from P: Q(0,0) = fy Tx, Q(0,3) = -fy cx Tx, Q(1,1) = fx Tx,
//   Q(1,3) = -fx cy Tx, Q(2,3) = fx fy Tx, Q(3,2) = -fy, Q(3,3) = fy (cx_left - cx_right);
// - each point is reprojectImageTo3D's with missing values handled (the image's smallest
//   disparity gives z = kMissingZ); a point with z = kMissingZ or infinite (zero disparity) is
//   NaN;
// - fields x, y, z float32 at 0, 4, 8 and, with use_color, rgb (packed b, g, r, 0 bytes) at 16:
//   point_step 16 or 32, as sensor_msgs' PointCloud2Modifier aligns them; with
//   avoid_point_cloud_padding, rgb at 12 and point_step 12 or 16;
// - colour from the left image (rgb8, rgba8, bgr8, bgra8 or mono8), of the disparity's size;
// - header = the disparity's; is_dense false; little-endian;
// - cloud.data is reused, without clearing, when it already has the cloud's size.
// Throws std::invalid_argument for a disparity other than 32FC1, a left image of another size or
// encoding, a CameraInfo without a focal length or a right one without a baseline (P[3] = 0).
// With the opencl backend the points are computed on the device by a kernel of robotperf's own
// (reprojectImageTo3D's operations in double: x, y and z within one float ulp of the cpu's, the
// rest identical), which needs a device with double precision; the disparity and left image
// are uploaded and the cloud downloaded per call.
class StereoPointCloudComputation;
using StereoPointCloudImplementation = Implementation<StereoPointCloudComputation>;
// cpu first, then opencl.
std::span<const StereoPointCloudImplementation> stereo_point_cloud_implementations();

// Not thread-safe: one per node.
class StereoPointCloudProcessor {
 public:
  // `backend`: an entry of stereo_point_cloud_implementations(), by name or itself. Throws
  // std::invalid_argument without its backend's device.
  explicit StereoPointCloudProcessor(std::string_view backend = "cpu");
  explicit StereoPointCloudProcessor(const StereoPointCloudImplementation& backend);
  ~StereoPointCloudProcessor();
  StereoPointCloudProcessor(StereoPointCloudProcessor&&) noexcept;
  StereoPointCloudProcessor& operator=(StereoPointCloudProcessor&&) noexcept;

  void compute(const msgs::Image& left_image, const msgs::CameraInfo& left_info,
               const msgs::CameraInfo& right_info, const msgs::DisparityImage& disparity,
               const StereoPointCloudParams& params, msgs::PointCloud2& cloud);

 private:
  std::unique_ptr<StereoPointCloudComputation> computation_;
};

}  // namespace robotperf::perception
