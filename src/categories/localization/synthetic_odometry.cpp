#include "robotperf/localization/synthetic_odometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/raycast_scene.hpp"

// Bit-identical frames on every platform: this file must be built with -ffp-contract=off, and
// everything that reaches a pixel uses IEEE-754 + - * /, sqrt and floor only (sine and cosine
// from their series, below).

namespace robotperf::localization {
namespace {

using perception::raycast::Box;
using perception::raycast::mix_bits;
using perception::raycast::Rectangle;
using perception::raycast::Scene;
using perception::raycast::Texture;
using perception::raycast::Vec3;

constexpr double kPi = 3.14159265358979323846;
constexpr double kLapSeconds = 15.0;
constexpr int kTilePx = 32;  // the ray caster culls the scene per tile of kTilePx x kTilePx

double portable_sin(double x) {
  return perception::portable_sin_cos(x).sin;
}

void validate(const SyntheticOdometryConfig& c) {
  if (c.width < 16 || c.height < 16 || c.width > 8192 || c.height > 8192)
    throw std::invalid_argument("synthetic odometry size must be 16 .. 8192 pixels a side");
  if (c.frames == 0) throw std::invalid_argument("synthetic odometry needs at least one frame");
  if (!(c.rate_hz > 0.0) || !std::isfinite(c.rate_hz))
    throw std::invalid_argument("synthetic odometry rate_hz must be positive");
  if (!(c.baseline_m > 0.0) || !std::isfinite(c.baseline_m))
    throw std::invalid_argument("synthetic odometry baseline_m must be positive");
  if (!(c.hfov_rad > 0.0 && c.hfov_rad < kPi))
    throw std::invalid_argument("synthetic odometry hfov_rad must be in (0, pi)");
  if (!(c.noise_stddev >= 0.0) || !std::isfinite(c.noise_stddev))
    throw std::invalid_argument("synthetic odometry noise_stddev must be finite and >= 0");
}

// An 11 m x 8 m x 3 m room (floor y = 1.3, ceiling y = -1.7) with two pillars inside the loops
// of the eight and crates and a shelf along the walls. Texture cells of 3 .. 10 cm give corners
// at every distance the room has (1 .. 11 m) without aliasing the nearest pixel footprints.
Scene room_scene() {
  Scene s;
  const double x0 = -5.5, x1 = 5.5, z0 = -4.0, z1 = 4.0, top = -1.7, floor_y = 1.3;
  s.rectangles.push_back({{x0, floor_y, z0},
                          {x1 - x0, 0.0, 0.0},
                          {0.0, 0.0, z1 - z0},
                          Texture{0.06, 211, {0.9, 0.8, 0.65}}});  // floor
  s.rectangles.push_back({{x0, top, z0},
                          {x1 - x0, 0.0, 0.0},
                          {0.0, 0.0, z1 - z0},
                          Texture{0.1, 223, {0.95, 0.95, 0.95}}});  // ceiling
  s.rectangles.push_back({{x0, top, z1},
                          {x1 - x0, 0.0, 0.0},
                          {0.0, floor_y - top, 0.0},
                          Texture{0.07, 227, {0.8, 0.9, 1.0}}});  // north wall
  s.rectangles.push_back({{x0, top, z0},
                          {x1 - x0, 0.0, 0.0},
                          {0.0, floor_y - top, 0.0},
                          Texture{0.05, 229, {1.0, 0.9, 0.8}}});  // south wall
  s.rectangles.push_back({{x0, top, z0},
                          {0.0, 0.0, z1 - z0},
                          {0.0, floor_y - top, 0.0},
                          Texture{0.06, 233, {0.8, 1.0, 0.85}}});  // west wall
  s.rectangles.push_back({{x1, top, z0},
                          {0.0, 0.0, z1 - z0},
                          {0.0, floor_y - top, 0.0},
                          Texture{0.08, 239, {1.0, 0.85, 0.9}}});  // east wall
  s.boxes.push_back(
      {{1.75, top, -0.25}, {2.25, floor_y, 0.25}, Texture{0.04, 241, {0.9, 0.9, 1.0}}});
  s.boxes.push_back(
      {{-2.25, top, -0.25}, {-1.75, floor_y, 0.25}, Texture{0.04, 251, {1.0, 1.0, 0.85}}});
  s.boxes.push_back({{-4.5, 0.5, 2.5}, {-3.7, floor_y, 3.3}, Texture{0.03, 257, {1.0, 0.8, 0.6}}});
  s.boxes.push_back({{3.0, 0.6, -3.6}, {3.9, floor_y, -2.8}, Texture{0.035, 263, {0.7, 0.8, 1.0}}});
  s.boxes.push_back({{-1.0, 0.7, 3.0}, {0.2, floor_y, 3.6}, Texture{0.03, 269, {0.9, 1.0, 0.7}}});
  s.boxes.push_back({{0.5, 0.4, -3.5}, {1.5, floor_y, -3.0}, Texture{0.04, 271, {1.0, 0.7, 0.7}}});
  s.boxes.push_back({{4.6, 0.2, 1.0}, {5.2, floor_y, 2.0}, Texture{0.035, 277, {0.8, 0.8, 0.6}}});
  s.boxes.push_back(
      {{-5.2, 0.0, -2.0}, {-4.6, floor_y, -0.8}, Texture{0.04, 281, {0.6, 0.9, 0.9}}});
  s.boxes.push_back({{-2.5, -0.6, 3.7}, {-1.0, -0.2, z1}, Texture{0.03, 283, {1.0, 0.95, 0.7}}});
  return s;
}

// A camera's centre and axes (the columns of its rotation) in the world.
struct View {
  Vec3 centre, x_axis, y_axis, z_axis;
};

View view_of(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d r = pose.linear();
  const Eigen::Vector3d t = pose.translation();
  return {{t.x(), t.y(), t.z()},
          {r(0, 0), r(1, 0), r(2, 0)},
          {r(0, 1), r(1, 1), r(2, 1)},
          {r(0, 2), r(1, 2), r(2, 2)}};
}

Eigen::Isometry3d pose_of(const View& v) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() << v.x_axis.x, v.y_axis.x, v.z_axis.x, v.x_axis.y, v.y_axis.y, v.z_axis.y,
      v.x_axis.z, v.y_axis.z, v.z_axis.z;
  pose.translation() << v.centre.x, v.centre.y, v.centre.z;
  return pose;
}

// The figure-of-eight x = 3 sin(a), z = 1.2 sin(2a), a = 0.3 + 2 pi t / 15 s (0.8 .. 1.6 m/s,
// turning round the pillars at up to 65 deg/s), facing along the path, with the height bobbing
// 8 cm, the pitch 3 degrees and the roll 1 degree.
View trajectory_view(double t_s) {
  const double a = 0.3 + 2.0 * kPi * t_s / kLapSeconds;
  const auto [sa, ca] = perception::portable_sin_cos(a);
  const auto [s2a, c2a] = perception::portable_sin_cos(2.0 * a);
  const Vec3 centre{3.0 * sa, 0.08 * portable_sin(3.0 * a), 1.2 * s2a};
  // Heading: the path's tangent in the floor plane (never zero: cos a = 0 makes |cos 2a| = 1).
  const double hx = 3.0 * ca;
  const double hz = 2.4 * c2a;
  const double norm = std::sqrt(hx * hx + hz * hz);
  const Vec3 forward{hx / norm, 0.0, hz / norm};
  const Vec3 right{forward.z, 0.0, -forward.x};
  const Vec3 down{0.0, 1.0, 0.0};
  // Pitch about the camera's x axis, then roll about its z axis.
  const auto [sp, cp] = perception::portable_sin_cos(0.05 * portable_sin(2.0 * a + 1.0));
  const auto [sr, cr] = perception::portable_sin_cos(0.02 * portable_sin(a + 0.5));
  const Vec3 pitched_down = cp * down + sp * forward;
  const Vec3 pitched_forward = cp * forward - sp * down;
  return {centre, cr * right + sr * pitched_down, cr * pitched_down - sr * right, pitched_forward};
}

struct Pinhole {
  double fx, fy, cx, cy;
};

Pinhole pinhole_of(const SyntheticOdometryConfig& c) {
  // perception's pinhole camera, as the dataset's CameraInfo states it.
  const msgs::CameraInfo info =
      perception::make_pinhole_camera_info(c.width, c.height, c.hfov_rad, {}, "");
  return {info.k[0], info.k[4], info.k[2], info.k[5]};
}

// The scene's primitives' corners in a camera's coordinates, for culling per tile.
struct CameraCorners {
  std::vector<std::array<Vec3, 8>> corners;  // rectangles first (4 used), then boxes
};

Vec3 to_camera(const View& view, Vec3 p) {
  const Vec3 rel = p - view.centre;
  return {dot(rel, view.x_axis), dot(rel, view.y_axis), dot(rel, view.z_axis)};
}

CameraCorners corners_in(const Scene& scene, const View& view) {
  CameraCorners out;
  for (const Rectangle& r : scene.rectangles) {
    std::array<Vec3, 8> c{};
    c[0] = to_camera(view, r.origin);
    c[1] = to_camera(view, r.origin + r.u);
    c[2] = to_camera(view, r.origin + r.v);
    c[3] = to_camera(view, r.origin + r.u + r.v);
    c[4] = c[5] = c[6] = c[7] = c[3];
    out.corners.push_back(c);
  }
  for (const Box& b : scene.boxes) {
    std::array<Vec3, 8> c{};
    for (int i = 0; i < 8; ++i) {
      c[static_cast<std::size_t>(i)] = to_camera(
          view,
          {(i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z});
    }
    out.corners.push_back(c);
  }
  return out;
}

// False only when every corner lies strictly outside one face of the pyramid of rays with
// normalised coordinates in [x_lo, x_hi] x [y_lo, y_hi] (or behind the camera): then no such ray
// can meet the (convex) primitive.
bool may_be_seen(const std::array<Vec3, 8>& c, double x_lo, double x_hi, double y_lo, double y_hi) {
  bool all_behind = true, all_left = true, all_right = true, all_above = true, all_below = true;
  for (const Vec3& p : c) {
    all_behind = all_behind && p.z <= 0.0;
    all_left = all_left && p.x < x_lo * p.z;
    all_right = all_right && p.x > x_hi * p.z;
    all_above = all_above && p.y < y_lo * p.z;
    all_below = all_below && p.y > y_hi * p.z;
  }
  return !(all_behind || all_left || all_right || all_above || all_below);
}

// Zero-mean noise of unit variance from a 32-bit hash: the sum of its four bytes as uniforms.
double unit_noise(uint32_t hash) {
  double sum = 0.0;
  for (int b = 0; b < 4; ++b) sum += ((hash >> (8 * b)) & 0xffU) + 0.5;
  return (sum / 256.0 - 2.0) * 1.7320508075688772;
}

// A surface's Texture sampled (as grey) on square texels, read back bilinearly.
class TexelGrid {
 public:
  TexelGrid(const Texture& texture, double s_lo, double s_hi, double t_lo, double t_hi)
      : texel_m_(texture.cell_m / kTexelsPerCell),
        per_texel_(1.0 / texel_m_),
        s0_(s_lo - texel_m_),
        t0_(t_lo - texel_m_),
        columns_(static_cast<int>(std::floor((s_hi - s_lo) / texel_m_)) + 4),
        rows_(static_cast<int>(std::floor((t_hi - t_lo) / texel_m_)) + 4),
        grey_(static_cast<std::size_t>(columns_) * static_cast<std::size_t>(rows_)) {
    for (int j = 0; j < rows_; ++j) {
      for (int i = 0; i < columns_; ++i) {
        uint8_t rgb[3];
        texture.colour(s0_ + i * texel_m_, t0_ + j * texel_m_, rgb);
        // Integer luma weights (ITU-R BT.601).
        grey_[index(i, j)] = static_cast<float>(77 * rgb[0] + 150 * rgb[1] + 29 * rgb[2]) / 256.0f;
      }
    }
  }

  double sample(double s, double t) const {
    const double x = (s - s0_) * per_texel_;
    const double y = (t - t0_) * per_texel_;
    // Truncation is floor here: points on the surface are at x, y >= 1 (the margin texel).
    const int i = std::clamp(static_cast<int>(x), 0, columns_ - 2);
    const int j = std::clamp(static_cast<int>(y), 0, rows_ - 2);
    const double ax = std::clamp(x - i, 0.0, 1.0);
    const double ay = std::clamp(y - j, 0.0, 1.0);
    const double top = grey_[index(i, j)] + ax * (grey_[index(i + 1, j)] - grey_[index(i, j)]);
    const double bottom =
        grey_[index(i, j + 1)] + ax * (grey_[index(i + 1, j + 1)] - grey_[index(i, j + 1)]);
    return top + ay * (bottom - top);
  }

 private:
  // A fifth of the finest noise cell: the bilinear read-back stays within a few grey levels of
  // Texture::colour (0.5 on average).
  static constexpr double kTexelsPerCell = 5.0;

  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(columns_) +
           static_cast<std::size_t>(i);
  }

  double texel_m_, per_texel_, s0_, t0_;
  int columns_, rows_;
  std::vector<float> grey_;
};

// The grey level of every surface point of a scene. Surface coordinates as raycast::Scene
// shades them: a rectangle's along u and v from its origin; a box face's along the two axes
// across it from the box's min corner, offset per axis so that faces do not repeat each other.
class Appearance {
 public:
  explicit Appearance(const Scene& scene) : scene_(scene) {
    for (const Rectangle& r : scene.rectangles) {
      const double lu = std::sqrt(dot(r.u, r.u));
      const double lv = std::sqrt(dot(r.v, r.v));
      rectangle_lengths_.push_back({lu, lv});
      rectangles_.emplace_back(r.texture, 0.0, lu, 0.0, lv);
    }
    for (const Box& b : scene.boxes) {
      const Vec3 size = b.max - b.min;
      boxes_.push_back({TexelGrid(b.texture, kAcrossX, kAcrossX + size.z, 0.0, size.y),
                        TexelGrid(b.texture, 0.0, size.x, kAcrossY, kAcrossY + size.z),
                        TexelGrid(b.texture, 0.0, size.x, 0.0, size.y)});
    }
  }

  // The grey level where the ray hit primitive `surface` (rectangles first, then boxes) at
  // `point`.
  double grey(std::size_t surface, Vec3 point) const {
    if (surface < rectangles_.size()) {
      const Rectangle& r = scene_.rectangles[surface];
      const Vec3 rel = point - r.origin;
      return rectangles_[surface].sample(dot(rel, r.u) / rectangle_lengths_[surface][0],
                                         dot(rel, r.v) / rectangle_lengths_[surface][1]);
    }
    const std::size_t box = surface - rectangles_.size();
    const Box& b = scene_.boxes[box];
    const Vec3 rel = point - b.min;
    const Vec3 size = b.max - b.min;
    // The face is the one the point lies closest to, relative to the box's size.
    const double across_x = std::min(rel.x, size.x - rel.x) / size.x;
    const double across_y = std::min(rel.y, size.y - rel.y) / size.y;
    const double across_z = std::min(rel.z, size.z - rel.z) / size.z;
    if (across_x <= across_y && across_x <= across_z) {
      return boxes_[box][0].sample(kAcrossX + rel.z, rel.y);
    }
    if (across_y <= across_z) return boxes_[box][1].sample(rel.x, kAcrossY + rel.z);
    return boxes_[box][2].sample(rel.x, rel.y);
  }

 private:
  static constexpr double kAcrossX = 7.0;
  static constexpr double kAcrossY = 13.0;

  const Scene& scene_;
  std::vector<TexelGrid> rectangles_;
  std::vector<std::array<double, 2>> rectangle_lengths_;
  std::vector<std::array<TexelGrid, 3>> boxes_;  // faces across x, y, z
};

struct RenderJob {
  View view;
  cv::Mat* image;
  uint32_t noise_key;  // frame and camera
};

// Rows [row_begin, row_end) of one view, tile by tile, each tile cast against only the
// primitives it may see (the same hits as the whole scene: culling is conservative and keeps
// the primitives' order).
void render_rows(const Scene& scene, const Appearance& appearance, const Pinhole& k,
                 const RenderJob& job, int row_begin, int row_end,
                 const SyntheticOdometryConfig& config) {
  const CameraCorners corners = corners_in(scene, job.view);
  const auto rectangles = scene.rectangles.size();
  Scene tile;
  std::vector<std::size_t> surface_of;  // a tile primitive's index in the scene
  tile.rectangles.reserve(rectangles);
  tile.boxes.reserve(scene.boxes.size());
  const int width = job.image->cols;
  const double margin_px = 1.0;
  for (int u0 = 0; u0 < width; u0 += kTilePx) {
    const int u1 = std::min(u0 + kTilePx, width);
    const double x_lo = (u0 - margin_px - k.cx) / k.fx;
    const double x_hi = (u1 - 1 + margin_px - k.cx) / k.fx;
    const double y_lo = (row_begin - margin_px - k.cy) / k.fy;
    const double y_hi = (row_end - 1 + margin_px - k.cy) / k.fy;
    tile.rectangles.clear();
    tile.boxes.clear();
    surface_of.clear();
    for (std::size_t i = 0; i < corners.corners.size(); ++i) {
      if (!may_be_seen(corners.corners[i], x_lo, x_hi, y_lo, y_hi)) continue;
      if (i < rectangles) {
        tile.rectangles.push_back(scene.rectangles[i]);
      } else {
        tile.boxes.push_back(scene.boxes[i - rectangles]);
      }
      surface_of.push_back(i);
    }
    for (int v = row_begin; v < row_end; ++v) {
      auto* row = job.image->ptr<uint8_t>(v);
      const Vec3 row_direction = ((v - k.cy) / k.fy) * job.view.y_axis + job.view.z_axis;
      for (int u = u0; u < u1; ++u) {
        const Vec3 direction = ((u - k.cx) / k.fx) * job.view.x_axis + row_direction;
        const perception::raycast::Hit hit = tile.cast(job.view.centre, direction, false);
        double grey =
            hit.found()
                ? appearance.grey(surface_of[static_cast<std::size_t>(hit.surface)], hit.point)
                : 0.0;
        if (config.noise_stddev > 0.0) {
          const uint32_t pixel =
              static_cast<uint32_t>(v) * static_cast<uint32_t>(width) + static_cast<uint32_t>(u);
          grey += config.noise_stddev *
                  unit_noise(mix_bits(mix_bits(config.noise_seed ^ job.noise_key) ^ pixel));
        }
        row[u] = static_cast<uint8_t>(grey < 0.0 ? 0.0 : (grey > 255.0 ? 255.0 : grey + 0.5));
      }
    }
  }
}

// Renders every job, split into bands of tile rows over the threads.
void render(const Scene& scene, const Pinhole& k, const std::vector<RenderJob>& jobs,
            const SyntheticOdometryConfig& config) {
  const Appearance appearance(scene);
  const int height = static_cast<int>(config.height);
  const int bands = (height + kTilePx - 1) / kTilePx;
  const int items = static_cast<int>(jobs.size()) * bands;
  cv::parallel_for_(cv::Range(0, items), [&](const cv::Range& range) {
    for (int item = range.start; item < range.end; ++item) {
      const RenderJob& job = jobs[static_cast<std::size_t>(item / bands)];
      const int band = item % bands;
      render_rows(scene, appearance, k, job, band * kTilePx, std::min(height, (band + 1) * kTilePx),
                  config);
    }
  });
}

View right_of(const View& left, double baseline_m) {
  View right = left;
  right.centre = left.centre + baseline_m * left.x_axis;
  return right;
}

uint32_t noise_key(uint32_t frame_index, uint32_t camera) {
  return mix_bits(frame_index * 2U + camera + 0x9e3779b9U);
}

}  // namespace

StereoCamera odometry_camera(const SyntheticOdometryConfig& config) {
  validate(config);
  const Pinhole k = pinhole_of(config);
  return {static_cast<int>(config.width),
          static_cast<int>(config.height),
          k.fx,
          k.fy,
          k.cx,
          k.cy,
          config.baseline_m};
}

Eigen::Isometry3d odometry_trajectory_pose(double t_s) {
  return pose_of(trajectory_view(t_s));
}

StereoPair render_odometry_stereo_pair(const Eigen::Isometry3d& left_in_world,
                                       const SyntheticOdometryConfig& config,
                                       uint32_t frame_index) {
  validate(config);
  const Pinhole k = pinhole_of(config);
  const Scene scene = room_scene();
  StereoPair pair{
      cv::Mat(static_cast<int>(config.height), static_cast<int>(config.width), CV_8UC1),
      cv::Mat(static_cast<int>(config.height), static_cast<int>(config.width), CV_8UC1)};
  const View left = view_of(left_in_world);
  render(scene, k,
         {{left, &pair.left, noise_key(frame_index, 0)},
          {right_of(left, config.baseline_m), &pair.right, noise_key(frame_index, 1)}},
         config);
  return pair;
}

OdometrySequence generate_odometry_sequence(const SyntheticOdometryConfig& config) {
  OdometrySequence sequence;
  sequence.camera = odometry_camera(config);
  const Pinhole k = pinhole_of(config);
  const Scene scene = room_scene();
  sequence.frames.resize(config.frames);
  std::vector<RenderJob> jobs;
  jobs.reserve(2 * static_cast<std::size_t>(config.frames));
  Eigen::Isometry3d first_inverse = Eigen::Isometry3d::Identity();
  for (uint32_t i = 0; i < config.frames; ++i) {
    OdometryFrame& frame = sequence.frames[i];
    frame.stamp_s = i / config.rate_hz;
    const View left = trajectory_view(frame.stamp_s);
    frame.left_in_world = pose_of(left);
    if (i == 0) first_inverse = frame.left_in_world.inverse();
    frame.left_in_first = first_inverse * frame.left_in_world;
    frame.left.create(static_cast<int>(config.height), static_cast<int>(config.width), CV_8UC1);
    frame.right.create(static_cast<int>(config.height), static_cast<int>(config.width), CV_8UC1);
    jobs.push_back({left, &frame.left, noise_key(i, 0)});
    jobs.push_back({right_of(left, config.baseline_m), &frame.right, noise_key(i, 1)});
  }
  render(scene, k, jobs, config);
  return sequence;
}

}  // namespace robotperf::localization
