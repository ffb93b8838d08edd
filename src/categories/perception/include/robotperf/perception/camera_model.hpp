#pragma once

// Building sensor_msgs/CameraInfo for ideal pinhole cameras (simulated sensors, tests).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::perception {

// sensor_msgs/distortion_models.hpp names.
inline constexpr std::string_view kPlumbBob = "plumb_bob";
inline constexpr std::string_view kRationalPolynomial = "rational_polynomial";
inline constexpr std::string_view kEquidistant = "equidistant";

// sin and cos from their series with IEEE-754 + - * / only: unlike libm's they give the same bits
// on every platform, so that datasets built from them hash the same everywhere. Absolute error
// below 1e-13 on [-pi, pi]; other angles are first reduced into it by whole turns.
struct SinCos {
  double sin = 0;
  double cos = 0;
};
SinCos portable_sin_cos(double x);

// A monocular pinhole camera with square pixels and horizontal field of view `hfov_rad`:
// fx = fy = (width / 2) / tan(hfov / 2), cx = width / 2, cy = height / 2 (the principal point
// at the image centre in the continuous pixel convention; Gazebo's camera plugin uses
// (width + 1) / 2 instead, a half-pixel apart), R = identity, P = [K | 0], no binning, full
// ROI. `distortion` is stored as D under `distortion_model`.
// Throws std::invalid_argument for a zero size or hfov outside (0, pi).
msgs::CameraInfo make_pinhole_camera_info(uint32_t width, uint32_t height, double hfov_rad,
                                          std::vector<double> distortion, std::string frame_id,
                                          std::string_view distortion_model = kPlumbBob);

}  // namespace robotperf::perception
