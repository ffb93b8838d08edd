#include "robotperf/perception/camera_model.hpp"

#include <numbers>
#include <stdexcept>
#include <utility>

namespace robotperf::perception {
namespace {

// tan from the sine and cosine series, with IEEE-754 + - * / only: unlike libm's tan it gives
// the same bits on every platform, so datasets built on these cameras hash the same everywhere.
// Relative error below 1e-13 on (-pi/2, pi/2).
double portable_tan(double x) {
  double sine = 0.0;
  double cosine = 0.0;
  double term = 1.0;  // x^n / n!
  for (int n = 0; n <= 40; ++n) {
    const double signed_term = (n / 2) % 2 == 0 ? term : -term;
    if (n % 2 == 0) {
      cosine += signed_term;
    } else {
      sine += signed_term;
    }
    term *= x / (n + 1);
  }
  return sine / cosine;
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
