#pragma once

// A deterministic rectified stereo sequence with ground-truth poses, the input of benchmark b1
// (stereo visual odometry): two ideal pinhole cameras (baseline along the left camera's +x) ride
// a figure-of-eight through a textured room with pillars and crates, ray-cast with
// perception's raycast::Scene so that every frame's pose is known exactly. Each surface's
// raycast::Texture is sampled once on texels a fifth of its noise cell and read back bilinearly
// (within a few grey levels of Texture::colour): shading every pixel with Texture::colour would
// take three times as long as the ray casting, and the default sequence casts 184 M rays.
//
// Frames use the optical convention: x right, y down, z forward. The world frame is the room's
// (y down, floor at y = +1.3 m, the eight crossing itself at the origin); the first frame's
// camera is not at the world origin, so the two poses a frame carries differ.

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace robotperf::localization {

struct SyntheticOdometryConfig {
  uint32_t width = 640;
  uint32_t height = 480;
  uint32_t frames = 300;  // 15 s at 20 Hz: one lap of the eight, 16.5 m
  double rate_hz = 20.0;
  double hfov_rad = 1.1;
  double baseline_m = 0.12;
  // Standard deviation of the zero-mean sensor noise added to every pixel, in grey levels
  // (0: none). Drawn from a hash of (noise_seed, frame, camera, pixel), not from <random>.
  double noise_stddev = 0.0;
  uint32_t noise_seed = 1;
};

// A rectified pinhole pair: both cameras have these intrinsics; the right camera sits
// baseline_m along the left's +x axis, with the same orientation.
struct StereoCamera {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double baseline_m = 0;
};

struct StereoPair {
  cv::Mat left;  // CV_8UC1, rectified
  cv::Mat right;
};

struct OdometryFrame {
  double stamp_s = 0;  // index / rate_hz
  cv::Mat left;        // CV_8UC1, rectified
  cv::Mat right;
  Eigen::Isometry3d left_in_world;  // T_world_left: left camera coordinates to world
  Eigen::Isometry3d left_in_first;  // T_first_left = T_world_first^-1 * T_world_left
};

struct OdometrySequence {
  StereoCamera camera;
  std::vector<OdometryFrame> frames;
};

// The pair's intrinsics: fx = fy = (width / 2) / tan(hfov / 2), cx = width / 2, cy = height / 2
// (perception::make_pinhole_camera_info's convention; pixel (u, v) sees the ray through
// ((u - cx) / fx, (v - cy) / fy, 1)). Throws std::invalid_argument as generate_odometry_sequence.
StereoCamera odometry_camera(const SyntheticOdometryConfig& config = {});

// The ground-truth left camera pose T_world_left at time t (s); periodic with the 15 s lap.
Eigen::Isometry3d odometry_trajectory_pose(double t_s);

// The room seen by the pair whose left camera is at `left_in_world`; `frame_index` selects the
// noise (when config.noise_stddev > 0). Same bytes on every machine for the same arguments.
// Throws std::invalid_argument as generate_odometry_sequence.
StereoPair render_odometry_stereo_pair(const Eigen::Isometry3d& left_in_world,
                                       const SyntheticOdometryConfig& config = {},
                                       uint32_t frame_index = 0);

// Frames 0 .. frames-1, frame k taken at t = k / rate_hz on odometry_trajectory_pose. Rendered
// in parallel (cv::parallel_for_); the bytes depend neither on the thread count nor the machine.
// Throws std::invalid_argument for a size outside 16 .. 8192 pixels a side, zero frames,
// rate_hz <= 0, baseline_m <= 0, hfov_rad outside (0, pi) or a negative or non-finite
// noise_stddev.
OdometrySequence generate_odometry_sequence(const SyntheticOdometryConfig& config = {});

}  // namespace robotperf::localization
