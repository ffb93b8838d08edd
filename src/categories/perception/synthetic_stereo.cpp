#include "robotperf/perception/synthetic_stereo.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/raycast_scene.hpp"

namespace robotperf::perception {
namespace {

using raycast::Box;
using raycast::Rectangle;
using raycast::Scene;
using raycast::Texture;
using raycast::Vec3;

// The scene at phase p in [0, 1): a room 1 m above the floor, objects between 1.6 m and 6 m
// (disparities about 9 to 33 px at 0.10 m baseline and hfov 1.089).
Scene stereo_scene(double p) {
  Scene s;
  s.rectangles.push_back({{-6.0, 1.0, 0.3},
                          {12.0, 0.0, 0.0},
                          {0.0, 0.0, 5.7},
                          Texture{0.03, 11, {0.95, 0.85, 0.7}}});  // floor
  s.rectangles.push_back({{-6.0, -4.0, 6.0},
                          {12.0, 0.0, 0.0},
                          {0.0, 5.0, 0.0},
                          Texture{0.05, 23, {0.8, 0.9, 1.0}}});  // back wall
  s.rectangles.push_back({{0.6, -0.7, 2.6},
                          {0.9, 0.0, 0.7},
                          {0.0, 1.1, 0.0},
                          Texture{0.02, 37, {1.0, 0.8, 0.8}}});  // slanted panel
  const double ax = -1.3 + 1.5 * p;
  s.boxes.push_back({{ax, 0.3, 1.6}, {ax + 0.5, 1.0, 2.1}, Texture{0.015, 41, {0.9, 1.0, 0.8}}});
  const double bz = 3.0 + 0.8 * p;
  s.boxes.push_back({{-0.3, -0.5, bz}, {0.3, 0.2, bz + 0.4}, Texture{0.03, 53, {1.0, 0.9, 0.6}}});
  s.boxes.push_back({{-1.6, -1.2, 4.0}, {-1.0, -0.4, 4.4}, Texture{0.03, 67, {0.7, 0.8, 1.0}}});
  return s;
}

void validate(const SyntheticStereoConfig& c) {
  if (c.width == 0 || c.height == 0 || c.width > 1u << 15 || c.height > 1u << 15)
    throw std::invalid_argument("synthetic stereo size must be 1 .. 32768 pixels a side");
  if (!(c.rate_hz > 0.0)) throw std::invalid_argument("synthetic stereo rate_hz must be positive");
  if (!(c.baseline_m > 0.0))
    throw std::invalid_argument("synthetic stereo baseline_m must be positive");
  if (!(c.hfov_rad > 0.0 && c.hfov_rad < std::numbers::pi))
    throw std::invalid_argument("synthetic stereo hfov_rad must be in (0, pi)");
}

// StereoFrame::disparity of a truth: StereoBM's 1/16 px, its invalid value where the truth has
// none.
msgs::DisparityImage matched_disparity(const msgs::DisparityImage& truth) {
  constexpr float kSteps = 16.0f;
  constexpr float kInvalid = -1.0f;  // min_disparity 0, less one
  msgs::DisparityImage out;
  out.header = truth.header;
  const cv::Mat in = image_view(truth.image);
  cv::Mat d = prepare_image(out.image, truth.image.header, "32FC1", in.cols, in.rows);
  for (int v = 0; v < in.rows; ++v) {
    const float* t = in.ptr<float>(v);
    float* row = d.ptr<float>(v);
    for (int u = 0; u < in.cols; ++u)
      row[u] = std::isnan(t[u]) ? kInvalid : std::round(t[u] * kSteps) / kSteps;
  }
  out.f = truth.f;
  out.t = truth.t;
  out.valid_window = truth.valid_window;
  out.min_disparity = 0.0f;
  out.max_disparity = 63.0f;
  out.delta_d = 1.0f / kSteps;
  return out;
}

}  // namespace

std::vector<StereoFrame> generate_stereo_sequence(const SyntheticStereoConfig& config) {
  validate(config);
  const int width = static_cast<int>(config.width);
  const int height = static_cast<int>(config.height);
  const msgs::CameraInfo left_info =
      perception::make_pinhole_camera_info(config.width, config.height, config.hfov_rad,
                                           {0.0, 0.0, 0.0, 0.0, 0.0}, config.left_frame_id);
  msgs::CameraInfo right_info =
      perception::make_pinhole_camera_info(config.width, config.height, config.hfov_rad,
                                           {0.0, 0.0, 0.0, 0.0, 0.0}, config.right_frame_id);
  const double f = left_info.k[0];
  const double cx = left_info.k[2];
  const double cy = left_info.k[5];
  const double baseline = config.baseline_m;
  right_info.p[3] = -f * baseline;
  const Vec3 left_origin{0.0, 0.0, 0.0};
  const Vec3 right_origin{baseline, 0.0, 0.0};

  std::vector<StereoFrame> frames(config.frames);
  for (uint32_t k = 0; k < config.frames; ++k) {
    const Scene scene = stereo_scene(static_cast<double>(k) / config.frames);
    StereoFrame& frame = frames[k];
    msgs::Header header;
    header.stamp = msgs::Time::from_ns(std::llround(k * 1e9 / config.rate_hz));
    header.frame_id = config.left_frame_id;
    msgs::Header right_header = header;
    right_header.frame_id = config.right_frame_id;
    cv::Mat left = perception::prepare_image(frame.left, header, "rgb8", width, height);
    cv::Mat right = perception::prepare_image(frame.right, right_header, "rgb8", width, height);
    cv::Mat truth = perception::prepare_image(frame.truth.image, header, "32FC1", width, height);

    auto render = [&](const Vec3& origin, cv::Mat& image, int v) {
      auto* row = image.ptr<uint8_t>(v);
      for (int u = 0; u < width; ++u) {
        const raycast::Hit hit = scene.cast(origin, {(u - cx) / f, (v - cy) / f, 1.0});
        for (int c = 0; c < 3; ++c) row[3 * u + c] = hit.rgb[c];
      }
    };
    cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
      const float nan = std::numeric_limits<float>::quiet_NaN();
      for (int v = rows.start; v < rows.end; ++v) {
        render(left_origin, left, v);
        render(right_origin, right, v);
        auto* truth_row = truth.ptr<float>(v);
        for (int u = 0; u < width; ++u) {
          truth_row[u] = nan;
          const raycast::Hit hit =
              scene.cast(left_origin, {(u - cx) / f, (v - cy) / f, 1.0}, false);
          if (!hit.found()) continue;
          const double z = hit.point.z;
          const double disparity = f * baseline / z;
          const double u_right = u - disparity;
          if (u_right < -0.5) continue;  // outside the right image
          // Seen by the right camera only if its ray through that point meets nothing before.
          const raycast::Hit seen =
              scene.cast(right_origin, {(u_right - cx) / f, (v - cy) / f, 1.0}, false);
          if (seen.surface != hit.surface || std::abs(seen.point.z - z) > 1e-6 * z) continue;
          truth_row[u] = static_cast<float>(disparity);
        }
      }
    });

    frame.left_info = left_info;
    frame.left_info.header = header;
    frame.right_info = right_info;
    frame.right_info.header = right_header;
    frame.truth.header = header;
    frame.truth.f = static_cast<float>(f);
    frame.truth.t = static_cast<float>(baseline);
    frame.truth.valid_window = {0, 0, config.height, config.width, false};
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        const float d = truth.at<float>(v, u);
        if (std::isnan(d)) continue;
        lo = std::min<double>(lo, d);
        hi = std::max<double>(hi, d);
      }
    }
    frame.truth.min_disparity = std::isfinite(lo) ? static_cast<float>(lo) : 0.0f;
    frame.truth.max_disparity = std::isfinite(hi) ? static_cast<float>(hi) : 0.0f;
    frame.truth.delta_d = 0.0f;
    frame.disparity = matched_disparity(frame.truth);
  }
  return frames;
}

}  // namespace robotperf::perception
