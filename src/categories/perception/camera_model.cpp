#include "robotperf/perception/camera_model.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

namespace robotperf::perception {
SinCos portable_sin_cos(double x) {
  // Into [-pi, pi], where the series is accurate; angles there are kept as they are, bit for bit.
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  if (x > std::numbers::pi || x < -std::numbers::pi) x -= kTwoPi * std::floor(x / kTwoPi + 0.5);
  SinCos out;
  double term = 1.0;  // x^n / n!
  for (int n = 0; n <= 40; ++n) {
    const double signed_term = (n / 2) % 2 == 0 ? term : -term;
    if (n % 2 == 0) {
      out.cos += signed_term;
    } else {
      out.sin += signed_term;
    }
    term *= x / (n + 1);
  }
  return out;
}

namespace {

double portable_tan(double x) {
  const SinCos sc = portable_sin_cos(x);
  return sc.sin / sc.cos;
}

}  // namespace

msgs::CameraInfo make_pinhole_camera_info(uint32_t width, uint32_t height, double hfov_rad,
                                          std::vector<double> distortion, std::string frame_id,
                                          std::string_view distortion_model) {
  if (width == 0 || height == 0) {
    throw std::invalid_argument("camera size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  }
  if (!(hfov_rad > 0.0 && hfov_rad < std::numbers::pi)) {
    throw std::invalid_argument("horizontal field of view must be in (0, pi) rad, got " +
                                std::to_string(hfov_rad));
  }
  const double f = (width / 2.0) / portable_tan(hfov_rad / 2.0);
  const double cx = width / 2.0;
  const double cy = height / 2.0;

  msgs::CameraInfo info;
  info.header.frame_id = std::move(frame_id);
  info.width = width;
  info.height = height;
  info.distortion_model = distortion_model;
  info.d = std::move(distortion);
  info.k = {f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0};
  info.r = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.p = {f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

}  // namespace robotperf::perception
