#pragma once

// A LaserScan from a depth image as ROS 2 depthimage_to_laserscan computes it, and from a point
// cloud as pointcloud_to_laserscan computes it, without the node plumbing. Both are cpu only: a6
// reads one row of 640 pixels and a7 scatters points into a few hundred beams by a running
// minimum, too little work per byte for a device to win back the upload.

#include <limits>
#include <numbers>
#include <string>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::perception {

// depthimage_to_laserscan's parameters, with its defaults.
struct DepthToScanParams {
  double scan_time = 0.033;  // s, copied into the scan
  double range_min = 0.45;   // m
  double range_max = 10.0;   // m
  int scan_height = 1;       // rows about the principal point whose per-column minimum is taken
  std::string output_frame = "camera_depth_frame";  // the scan's frame_id; "" keeps the image's
};

// Writes the scan of a depth image and its CameraInfo into `scan`, as DepthImageToLaserScan does:
// - the camera model is image_geometry's (fx, cx, cy from P; D applied by cv::undistortPoints
//   when not all zero); angle_max is the angle between the rays of pixels (0, cy) and (cx, cy),
//   angle_min minus that between (cx, cy) and (width - 1, cy), one beam per column;
// - over the scan_height rows from int(cy - scan_height / 2.0), each column's range is the
//   planar distance hypot(x, z) of its point, put in the beam of its angle atan2(cx - u, fx)
//   when it beats the beam's value: a finite range in [range_min, range_max] beats a non-finite
//   one or a longer one, and +-inf beats NaN; beams without one are NaN;
// - depth 32FC1 in metres (valid when finite) or 16UC1 in millimetres (valid when non-zero).
// Throws std::invalid_argument for another encoding, an image under two columns, a CameraInfo
// without a focal length, or a scan_height the image cannot hold about cy.
void depth_image_to_laser_scan(const msgs::Image& depth, const msgs::CameraInfo& info,
                               const DepthToScanParams& params, msgs::LaserScan& scan);

// pointcloud_to_laserscan's parameters, with its defaults (min_height is the smallest positive
// double, as the node declares it).
struct CloudToScanParams {
  std::string target_frame;  // "" = the cloud's own frame
  double min_height = std::numeric_limits<double>::min();
  double max_height = std::numeric_limits<double>::max();
  double angle_min = -std::numbers::pi;
  double angle_max = std::numbers::pi;
  double angle_increment = std::numbers::pi / 180.0;
  double scan_time = 1.0 / 30.0;
  double range_min = 0.0;
  double range_max = std::numeric_limits<double>::max();
  bool use_inf = true;  // beams without a point: +inf, or else range_max + inf_epsilon
  double inf_epsilon = 1.0;
};

// Throws std::invalid_argument, naming the parameter, unless the angles make a scan of 1 to 2^20
// beams and the height and range bounds are ordered.
void check(const CloudToScanParams& params);

// Writes the scan of a cloud's float32 x, y, z points into `scan`, as PointCloudToLaserScanNode
// does: ceil((angle_max - angle_min) / angle_increment) beams (in float, as the message holds the
// angles); a point that is not NaN, with z in [min_height, max_height], hypot(x, y) in [range_min,
// range_max] and atan2(y, x) in [angle_min, angle_max] lowers the range of beam
// int((angle - angle_min) / angle_increment) to its own (one past the last beam, which the node
// would write, is dropped). The graph has no tf: a target_frame other than the cloud's frame is
// refused, as the node refuses a cloud tf cannot transform.
// Throws std::invalid_argument for such a frame, a cloud without float32 x, y, z or whose data
// does not hold its points, a big-endian cloud, or parameters check() refuses.
void point_cloud_to_laser_scan(const msgs::PointCloud2& cloud, const CloudToScanParams& params,
                               msgs::LaserScan& scan);

}  // namespace robotperf::perception
