#include "robotperf/perception/synthetic_depth.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/raycast_scene.hpp"

namespace robotperf::perception {
namespace {

using raycast::Rectangle;
using raycast::Scene;
using raycast::Texture;
using raycast::Vec3;

// A 5.5 m x 3.2 m room, camera 1.2 m above the floor; the back wall at 7.5 m has a doorway onto
// a corridor that ends at 10.5 m, beyond the sensor's range.
Scene depth_scene(double p) {
  Scene s;
  s.rectangles.push_back({{-2.5, 1.2, 0.2},
                          {5.5, 0.0, 0.0},
                          {0.0, 0.0, 7.3},
                          Texture{0.04, 101, {0.9, 0.8, 0.6}}});  // floor
  s.rectangles.push_back({{-2.5, -2.0, 0.2},
                          {5.5, 0.0, 0.0},
                          {0.0, 0.0, 7.3},
                          Texture{0.08, 103, {0.95, 0.95, 0.95}}});  // ceiling
  s.rectangles.push_back({{-2.5, -2.0, 0.2},
                          {0.0, 0.0, 7.3},
                          {0.0, 3.2, 0.0},
                          Texture{0.05, 107, {0.7, 0.9, 0.7}}});  // left wall
  s.rectangles.push_back({{3.0, -2.0, 0.2},
                          {0.0, 0.0, 7.3},
                          {0.0, 3.2, 0.0},
                          Texture{0.05, 109, {0.9, 0.7, 0.7}}});  // right wall
  Rectangle back{
      {-2.5, -2.0, 7.5}, {5.5, 0.0, 0.0}, {0.0, 3.2, 0.0}, Texture{0.06, 113, {0.7, 0.8, 0.95}}};
  back.has_hole = true;  // doorway x in [0.6, 1.6], from y = -0.8 down to the floor
  back.hole_a0 = 3.1 / 5.5;
  back.hole_a1 = 4.1 / 5.5;
  back.hole_b0 = 1.2 / 3.2;
  back.hole_b1 = 1.0 + 1e-9;
  s.rectangles.push_back(back);
  s.rectangles.push_back({{0.6, 1.2, 7.5},
                          {1.0, 0.0, 0.0},
                          {0.0, 0.0, 3.0},
                          Texture{0.04, 127, {0.9, 0.8, 0.6}}});  // corridor floor
  s.rectangles.push_back({{-1.0, -2.0, 10.5},
                          {4.0, 0.0, 0.0},
                          {0.0, 3.2, 0.0},
                          Texture{0.06, 131, {0.8, 0.8, 0.8}}});  // corridor end
  const double x1 = -0.8 + 1.1 * p;
  s.boxes.push_back({{x1, 0.2, 0.6}, {x1 + 0.3, 0.6, 0.9}, Texture{0.01, 137, {1.0, 0.6, 0.5}}});
  const double z2 = 2.5 + 1.0 * p;
  s.boxes.push_back({{0.8, 0.4, z2}, {1.5, 1.2, z2 + 0.7}, Texture{0.03, 139, {0.6, 0.7, 1.0}}});
  s.boxes.push_back({{-1.8, -0.5, 4.5}, {-1.2, 1.2, 5.0}, Texture{0.03, 149, {0.9, 0.9, 0.5}}});
  return s;
}

void validate(const SyntheticDepthConfig& c) {
  if (c.width == 0 || c.height == 0 || c.width > 1u << 15 || c.height > 1u << 15)
    throw std::invalid_argument("synthetic depth size must be 1 .. 32768 pixels a side");
  if (!(c.rate_hz > 0.0)) throw std::invalid_argument("synthetic depth rate_hz must be positive");
  if (!(c.min_range_m > 0.0 && c.max_range_m > c.min_range_m && c.max_range_m < 65.0))
    throw std::invalid_argument("synthetic depth range must satisfy 0 < min < max < 65 m");
  if (!(c.hfov_rad > 0.0 && c.hfov_rad < std::numbers::pi))
    throw std::invalid_argument("synthetic depth hfov_rad must be in (0, pi)");
}

// The organised xyz cloud of a frame's true depth.
msgs::PointCloud2 body_cloud(const cv::Mat& truth, const msgs::CameraInfo& info,
                             msgs::Header header) {
  msgs::PointCloud2 cloud;
  cloud.header = std::move(header);
  cloud.height = static_cast<uint32_t>(truth.rows);
  cloud.width = static_cast<uint32_t>(truth.cols);
  constexpr uint8_t kFloat32 = msgs::PointField::kFloat32;
  cloud.fields = {{"x", 0, kFloat32, 1}, {"y", 4, kFloat32, 1}, {"z", 8, kFloat32, 1}};
  cloud.is_bigendian = false;
  cloud.point_step = 16;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.is_dense = false;
  cloud.data.assign(std::size_t{cloud.row_step} * cloud.height, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < truth.rows; ++v) {
    const double* row = truth.ptr<double>(v);
    uint8_t* point = cloud.data.data() + std::size_t{cloud.row_step} * static_cast<std::size_t>(v);
    for (int u = 0; u < truth.cols; ++u, point += cloud.point_step) {
      float xyz[3] = {nan, nan, nan};
      if (!std::isnan(row[u])) {
        const BodyPoint p = camera_body_point(info, u, v, row[u]);
        xyz[0] = static_cast<float>(p.x);
        xyz[1] = static_cast<float>(p.y);
        xyz[2] = static_cast<float>(p.z);
      }
      std::memcpy(point, xyz, sizeof xyz);
    }
  }
  return cloud;
}

}  // namespace

BodyPoint camera_body_point(const msgs::CameraInfo& info, double u, double v, double z) {
  const double fx = info.p[0], fy = info.p[5], cx = info.p[2], cy = info.p[6];
  return {z, -(u - cx) * z / fx, -(v - cy) * z / fy};
}

std::vector<DepthFrame> generate_depth_sequence(const SyntheticDepthConfig& config) {
  validate(config);
  const int width = static_cast<int>(config.width);
  const int height = static_cast<int>(config.height);
  const msgs::CameraInfo info = perception::make_pinhole_camera_info(
      config.width, config.height, config.hfov_rad, {0.0, 0.0, 0.0, 0.0, 0.0}, config.frame_id);
  const double fx = info.p[0];
  const double fy = info.p[5];
  const double cx = info.p[2];
  const double cy = info.p[6];

  std::vector<DepthFrame> frames(config.frames);
  for (uint32_t k = 0; k < config.frames; ++k) {
    const Scene scene = depth_scene(static_cast<double>(k) / config.frames);
    DepthFrame& frame = frames[k];
    msgs::Header header;
    header.stamp = msgs::Time::from_ns(std::llround(k * 1e9 / config.rate_hz));
    header.frame_id = config.frame_id;
    cv::Mat depth = perception::prepare_image(frame.depth, header, "32FC1", width, height);
    cv::Mat depth_mm = perception::prepare_image(frame.depth_mm, header, "16UC1", width, height);
    cv::Mat colour = perception::prepare_image(frame.colour, header, "rgb8", width, height);
    cv::Mat truth = perception::prepare_image(frame.truth_depth, header, "64FC1", width, height);
    cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v) {
        auto* depth_row = depth.ptr<float>(v);
        auto* mm_row = depth_mm.ptr<uint16_t>(v);
        auto* colour_row = colour.ptr<uint8_t>(v);
        auto* truth_row = truth.ptr<double>(v);
        for (int u = 0; u < width; ++u) {
          // Direction with unit z: the distance along it is the depth Z.
          const raycast::Hit hit = scene.cast({0.0, 0.0, 0.0}, {(u - cx) / fx, (v - cy) / fy, 1.0});
          for (int c = 0; c < 3; ++c) colour_row[3 * u + c] = hit.rgb[c];
          const double z = hit.found() ? hit.point.z : std::numeric_limits<double>::infinity();
          if (z >= config.min_range_m && z <= config.max_range_m) {
            depth_row[u] = static_cast<float>(z);
            mm_row[u] = static_cast<uint16_t>(std::floor(z * 1000.0 + 0.5));
            truth_row[u] = z;
          } else {
            depth_row[u] = std::numeric_limits<float>::quiet_NaN();
            mm_row[u] = 0;
            truth_row[u] = std::numeric_limits<double>::quiet_NaN();
          }
        }
      }
    });
    frame.info = info;
    frame.info.header = header;
    msgs::Header body = header;
    body.frame_id = config.body_frame_id;
    frame.cloud = body_cloud(truth, info, std::move(body));
  }
  return frames;
}

}  // namespace robotperf::perception
