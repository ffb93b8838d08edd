#pragma once

// A deterministic synthetic camera stream standing in for RobotPerf's perception/image source
// (recorded in simulation, not available): a distorted pinhole camera looking at a textured
// checkerboard with a box moving across it.

#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::perception {

struct SyntheticCameraConfig {
  uint32_t width = 640;
  uint32_t height = 480;
  uint32_t frames = 68;
  double rate_hz = 30.0;
  double hfov_rad = 1.047;
  // plumb_bob k1, k2, p1, p2[, k3].
  std::vector<double> distortion{-0.25, 0.12, -0.00028, -5e-5, 0.0};
  std::string frame_id = "camera_optical_frame";
};

struct CameraFrame {
  msgs::Image image;  // rgb8, as the distorted lens sees the scene
  msgs::CameraInfo info;
};

// Edge of the scene's checkerboard tiles in pixels of the ideal (undistorted) image. Tile
// corners lie at (kCheckerTilePx * i - 0.5, kCheckerTilePx * j - 0.5) in OpenCV's pixel-centre
// coordinates of the ideal image.
inline constexpr int kCheckerTilePx = 40;

// Frames 0 .. frames-1; frame k is stamped k / rate_hz seconds (rounded to the nanosecond).
// Camera model: perception::make_pinhole_camera_info(width, height, hfov_rad, distortion,
// frame_id), plumb_bob. The same config gives the same bytes on every run and machine.
// Throws std::invalid_argument for a zero size, rate_hz <= 0, or distortion not of 4 or 5
// coefficients.
std::vector<CameraFrame> generate_camera_sequence(const SyntheticCameraConfig& config = {});

// Frame `index` as an ideal, distortion-free camera with the same K sees it: what rectifying
// the generated frame approximates. Header as in generate_camera_sequence.
msgs::Image render_ideal_camera_frame(const SyntheticCameraConfig& config, uint32_t index);

// Content hash over every field of every image and camera info, in order ("fnv1a64:...").
std::string camera_sequence_hash(const std::vector<CameraFrame>& frames);

}  // namespace robotperf::perception
