#pragma once

// A deterministic rectified stereo sequence with per-pixel ground-truth disparity, standing in
// for RobotPerf's perception/image3 source (recorded in simulation, not available): two ideal
// pinhole cameras (baseline along +x) looking at a textured room (floor, back wall) with boxes
// and a slanted panel moving through it, ray-cast so that every pixel's depth is known exactly.

#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"

namespace robotperf::perception {

struct SyntheticStereoConfig {
  uint32_t width = 640;
  uint32_t height = 480;
  uint32_t frames = 10;
  double rate_hz = 10.0;
  double hfov_rad = 1.089;
  double baseline_m = 0.10;
  std::string left_frame_id = "left_camera_optical_frame";
  std::string right_frame_id = "right_camera_optical_frame";
};

struct StereoFrame {
  msgs::Image left;  // rgb8, rectified
  msgs::Image right;
  msgs::CameraInfo left_info;   // make_pinhole_camera_info, D all zero
  msgs::CameraInfo right_info;  // as left, P[3] = -fx * baseline
  // Ground truth in the left view: 32FC1 disparity f * baseline / Z (NaN where the point is
  // hidden from the right camera or falls outside its image), f, t = baseline, valid_window =
  // whole image, min/max disparity of the known pixels, delta_d 0.
  msgs::DisparityImage truth;
  // The truth as stereo_image_proc's disparity node would publish it were its matcher exact
  // (StereoBM at its defaults): 32FC1 in steps of 1/16 px, -1 (min_disparity - 1) where the truth
  // has none, header, f and t as the truth's, valid_window = whole image, min_disparity 0,
  // max_disparity 63, delta_d 1/16. What stereo_image_proc's point cloud node takes.
  msgs::DisparityImage disparity;
};

// Frames 0 .. frames-1, frame k stamped k / rate_hz s. Every pixel, and its truth, is the scene
// seen through the pixel centre (textures are coarse enough not to alias). Same bytes on every
// machine.
// Throws std::invalid_argument for a zero size, rate_hz <= 0, baseline <= 0 or hfov outside
// (0, pi).
std::vector<StereoFrame> generate_stereo_sequence(const SyntheticStereoConfig& config = {});

}  // namespace robotperf::perception
