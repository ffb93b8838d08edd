#pragma once

// A deterministic registered depth + colour sequence of a known scene, standing in for
// RobotPerf's perception/depth_image1 source: an ideal pinhole RGB-D camera in a textured room
// (floor, side wall, back wall with a doorway to a corridor beyond the sensor's range) with boxes
// moving through it, ray-cast so that every pixel's true depth is known.

#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::perception {

struct SyntheticDepthConfig {
  uint32_t width = 640;
  uint32_t height = 480;
  uint32_t frames = 20;
  double rate_hz = 30.0;
  double hfov_rad = 1.089;
  double min_range_m = 0.05;  // the sensor reports no depth outside [min, max]
  double max_range_m = 8.0;
  std::string frame_id = "camera_color_optical_frame";
  // The frame of the cloud: the camera's body, x forward, y left, z up (REP 103), at the optical
  // frame's origin.
  std::string body_frame_id = "camera_link";
};

struct DepthFrame {
  msgs::Image depth;      // 32FC1 metres, NaN where there is no depth
  msgs::Image depth_mm;   // 16UC1 millimetres (rounded), 0 where there is no depth
  msgs::Image colour;     // rgb8, registered to the depth image
  msgs::CameraInfo info;  // make_pinhole_camera_info, D all zero
  // Ground truth: 64FC1 true Z of the pixel centre's ray in metres, NaN where there is no depth.
  // The true point is ((u - cx) Z / fx, (v - cy) Z / fy, Z).
  msgs::Image truth_depth;
  // The true depth's points in the body frame, as a 3D sensor's driver publishes its cloud:
  // organised, float32 x, y, z at 0, 4, 8, point_step 16 (as PointCloud2Modifier aligns "xyz"),
  // NaN where there is no depth; header = the depth's with body_frame_id.
  msgs::PointCloud2 cloud;
};

struct BodyPoint {
  double x, y, z;
};

// Pixel (u, v) at depth z of the optical frame (x right, y down, z forward) of `info`'s camera,
// in the body frame (x forward, y left, z up).
BodyPoint camera_body_point(const msgs::CameraInfo& info, double u, double v, double z);

// Frames 0 .. frames-1, frame k stamped k / rate_hz s, one sample per pixel at its centre. Same
// bytes on every machine. Throws std::invalid_argument for a zero size, rate_hz <= 0, a bad
// range or hfov outside (0, pi).
std::vector<DepthFrame> generate_depth_sequence(const SyntheticDepthConfig& config = {});

}  // namespace robotperf::perception
