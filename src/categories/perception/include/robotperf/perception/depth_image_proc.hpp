#pragma once

// Depth image to coloured point cloud as ROS 2 depth_image_proc's PointCloudXyzrgbNode computes
// it, without the node plumbing.

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/perception/image_proc.hpp"

namespace robotperf::perception {

// Byte layout of the cloud, as sensor_msgs' PointCloud2Modifier lays out fields "xyz", "rgb":
// x, y, z float32 at 0, 4, 8, padding to 16; rgb (packed b, g, r, 0 bytes in a float32) at 16,
// padding to 32.
inline constexpr uint32_t kXyzrgbOffsetX = 0;
inline constexpr uint32_t kXyzrgbOffsetY = 4;
inline constexpr uint32_t kXyzrgbOffsetZ = 8;
inline constexpr uint32_t kXyzrgbOffsetRgb = 16;
inline constexpr uint32_t kXyzrgbPointStep = 32;

struct PointCloudXyzrgbParams {
  // Depth given to invalid pixels, in metres; 0 makes them NaN points (depth_image_proc's
  // "range_max", default 0).
  double range_max = 0.0;
};

// Builds the organised cloud (height x width of the depth image) of a registered depth image and
// its colour image, with the colour camera's CameraInfo (fx, fy, cx, cy from P, as
// image_geometry reads them):
// - depth: 32FC1 in metres (valid when finite) or 16UC1 in millimetres (valid when non-zero);
//   x = (u - cx) * z / fx, y = (v - cy) * z / fy, in float as depth_image_proc computes them;
//   invalid depth gives NaN x, y, z (or range_max when set);
// - colour: rgb8, rgba8, bgr8, bgra8 or mono8; resized (bilinear) to the depth size when it
//   differs, the camera model then scaled by depth width / colour width;
// - header = the depth image's; is_dense false; little-endian;
// - cloud.data is reused, without clearing, when it already has the cloud's size (its padding
//   bytes are then left as they are: zero when this function made the cloud).
// Throws std::invalid_argument for other encodings, differing frame_ids, a CameraInfo without a
// focal length, or a bad image.
// With the opencl or cuda backend the points are computed on the device by a kernel of
// robotperf's own (same float operations, no contraction into fused multiply-adds: the same bits
// as the CPU's), the depth and colour uploaded and the cloud downloaded per call; a colour image
// of another size is resized on the device (bilinear, within 1 of the CPU's per channel).
void point_cloud_xyzrgb(const msgs::Image& depth, const msgs::Image& colour,
                        const msgs::CameraInfo& info, const PointCloudXyzrgbParams& params,
                        msgs::PointCloud2& cloud, std::string_view backend = "cpu");

class PointCloudComputation;
using PointCloudImplementation = Implementation<PointCloudComputation>;
// The implementations of PointCloudXyzrgbProcessor's computation: cpu first, then opencl and cuda.
std::span<const PointCloudImplementation> point_cloud_implementations();

// point_cloud_xyzrgb() keeping what a node keeps from message to message on its backend (with
// cuda its stream and buffers, with opencl its device images and kernel; the free function's are
// for its call only). Not thread-safe: one per node.
class PointCloudXyzrgbProcessor {
 public:
  // `backend`: an entry of point_cloud_implementations(), by name or itself. Throws
  // std::invalid_argument without its backend's device (cuda_device(), opencl_device()).
  explicit PointCloudXyzrgbProcessor(std::string_view backend = "cpu");
  explicit PointCloudXyzrgbProcessor(const PointCloudImplementation& backend);
  ~PointCloudXyzrgbProcessor();
  PointCloudXyzrgbProcessor(PointCloudXyzrgbProcessor&&) noexcept;
  PointCloudXyzrgbProcessor& operator=(PointCloudXyzrgbProcessor&&) noexcept;

  void compute(const msgs::Image& depth, const msgs::Image& colour, const msgs::CameraInfo& info,
               const PointCloudXyzrgbParams& params, msgs::PointCloud2& cloud);

 private:
  // The points on the backend, with what it keeps there from one message to the next.
  std::unique_ptr<PointCloudComputation> computation_;
};

}  // namespace robotperf::perception
