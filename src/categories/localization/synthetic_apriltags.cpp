#include "robotperf/localization/synthetic_apriltags.hpp"

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <thread>

#include "quaternion.hpp"
#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/raycast_scene.hpp"

namespace robotperf::localization {
namespace {

using perception::portable_sin_cos;
using perception::raycast::Vec3;

// splitmix64: a stream of its own per frame, so frames can be rendered in any order.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Unit variance, from four uniforms (Irwin-Hall): + - * / only, unlike libm-based methods.
  double normal() {
    return (uniform() + uniform() + uniform() + uniform() - 2.0) * 1.7320508075688772;
  }

 private:
  uint64_t state_;
};

struct Mat3 {
  double m[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double operator()(int r, int c) const { return m[3 * r + c]; }
  Vec3 column(int c) const { return {m[c], m[3 + c], m[6 + c]}; }
};

Mat3 operator*(const Mat3& a, const Mat3& b) {
  Mat3 out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      out.m[3 * r + c] = a(r, 0) * b(0, c) + a(r, 1) * b(1, c) + a(r, 2) * b(2, c);
    }
  }
  return out;
}

Mat3 rotation(int axis, double angle) {
  const auto [s, c] = portable_sin_cos(angle);
  switch (axis) {
    case 0:
      return {{1, 0, 0, 0, c, -s, 0, s, c}};
    case 1:
      return {{c, 0, s, 0, 1, 0, -s, 0, c}};
    default:
      return {{c, -s, 0, s, c, 0, 0, 0, 1}};
  }
}

// The inverse by the adjugate; the matrices here are well conditioned homographies.
Mat3 inverse(const Mat3& a) {
  const double* m = a.m;
  Mat3 adj{{m[4] * m[8] - m[5] * m[7], m[2] * m[7] - m[1] * m[8], m[1] * m[5] - m[2] * m[4],
            m[5] * m[6] - m[3] * m[8], m[0] * m[8] - m[2] * m[6], m[2] * m[3] - m[0] * m[5],
            m[3] * m[7] - m[4] * m[6], m[1] * m[6] - m[0] * m[7], m[0] * m[4] - m[1] * m[3]}};
  const double det = m[0] * adj.m[0] + m[1] * adj.m[3] + m[2] * adj.m[6];
  for (double& x : adj.m) x /= det;
  return adj;
}

// The 36h11 family, as libapriltag defines it.
struct FamilyDeleter {
  void operator()(apriltag_family_t* f) const { tag36h11_destroy(f); }
};
using Family = std::unique_ptr<apriltag_family_t, FamilyDeleter>;

constexpr int kCells = 10;       // tag36h11's total width in cells, its white border included
constexpr int kBorderCells = 8;  // the black border square, whose edge is the tag size
constexpr int kSamples = 4;      // per pixel and axis: anti-aliasing by a 4x4 box filter

// 1 = white, row 0 at the top as printed.
using Bitmap = std::array<uint8_t, kCells * kCells>;

Bitmap tag_bitmap(apriltag_family_t* family, int id) {
  image_u8_t* image = apriltag_to_image(family, id);
  Bitmap bits{};
  for (int r = 0; r < kCells; ++r) {
    for (int c = 0; c < kCells; ++c) {
      bits[static_cast<std::size_t>(r * kCells + c)] =
          image->buf[r * image->stride + c] > 127 ? 1 : 0;
    }
  }
  // Debian's libapriltag does not export image_u8_destroy; the image and its pixels are two
  // malloc'd blocks.
  std::free(image->buf);
  std::free(image);
  return bits;
}

// A square that decodes as no tag: the white and black borders of a tag around random bits.
Bitmap distractor_bitmap(Random& random) {
  Bitmap bits{};
  for (int r = 0; r < kCells; ++r) {
    for (int c = 0; c < kCells; ++c) {
      const bool outer = r == 0 || c == 0 || r == kCells - 1 || c == kCells - 1;
      const bool border = !outer && (r == 1 || c == 1 || r == kCells - 2 || c == kCells - 2);
      bits[static_cast<std::size_t>(r * kCells + c)] =
          outer ? 1 : (border ? 0 : static_cast<uint8_t>(random.next() & 1));
    }
  }
  return bits;
}

struct Camera {
  double f, cx, cy;
  uint32_t width, height;
  double u(Vec3 p) const { return f * p.x / p.z + cx; }
  double v(Vec3 p) const { return f * p.y / p.z + cy; }
};

struct Box2 {
  int u0, v0, u1, v1;  // inclusive
  bool overlaps(const Box2& o, int margin) const {
    return !(u1 + margin < o.u0 || o.u1 + margin < u0 || v1 + margin < o.v0 || o.v1 + margin < v0);
  }
};

// A planar square of kCells x kCells cells at pose (rotation, centre) in the camera frame.
struct PlacedSquare {
  int id = -1;  // -1: a distractor
  Bitmap bits{};
  Mat3 rotation;
  Vec3 centre;
  double cell = 0;  // m
  double dark = 0, light = 0;
  Mat3 pixel_to_plane;  // pixel (u, v, 1) -> (X, Y, 1) on the square, up to scale
  Box2 box{};
  double visible = 1.0;

  // Tag-frame point (x right, y up on the printed tag) in the camera frame.
  Vec3 point(double x, double y) const {
    return centre + x * rotation.column(0) + y * rotation.column(1);
  }
  // The cell under pixel position (u, v) and its shade; false when outside the square.
  bool sample(double u, double v, double& shade) const {
    const Mat3& h = pixel_to_plane;
    const double w = h(2, 0) * u + h(2, 1) * v + h(2, 2);
    const double x = (h(0, 0) * u + h(0, 1) * v + h(0, 2)) / w;
    const double y = (h(1, 0) * u + h(1, 1) * v + h(1, 2)) / w;
    const double half = 0.5 * kCells * cell;
    const double col = std::floor((x + half) / cell);
    const double row = std::floor((half - y) / cell);
    if (col < 0.0 || row < 0.0 || col >= kCells || row >= kCells) return false;
    shade = bits[static_cast<std::size_t>(row * kCells + col)] ? light : dark;
    return true;
  }
};

bool place(PlacedSquare& s, const Camera& camera, const std::vector<PlacedSquare>& placed) {
  const double half = 0.5 * kCells * s.cell;
  double u_min = 1e300, u_max = -1e300, v_min = 1e300, v_max = -1e300;
  for (const auto& [x, y] : {std::pair{-half, -half}, {half, -half}, {half, half}, {-half, half}}) {
    const Vec3 p = s.point(x, y);
    if (!(p.z > 0.1)) return false;
    u_min = std::min(u_min, camera.u(p));
    u_max = std::max(u_max, camera.u(p));
    v_min = std::min(v_min, camera.v(p));
    v_max = std::max(v_max, camera.v(p));
  }
  // The whole square, its white border included, two pixels inside the image.
  if (u_min < 2.0 || v_min < 2.0 || u_max > camera.width - 3.0 || v_max > camera.height - 3.0) {
    return false;
  }
  s.box = {static_cast<int>(std::floor(u_min)), static_cast<int>(std::floor(v_min)),
           static_cast<int>(std::ceil(u_max)), static_cast<int>(std::ceil(v_max))};
  for (const PlacedSquare& other : placed) {
    if (s.box.overlaps(other.box, 6)) return false;
  }
  // Plane (x, y) -> pixel is K [r1 r2 t].
  const Vec3 r1 = s.rotation.column(0);
  const Vec3 r2 = s.rotation.column(1);
  const Mat3 plane_to_pixel{{camera.f * r1.x + camera.cx * r1.z, camera.f * r2.x + camera.cx * r2.z,
                             camera.f * s.centre.x + camera.cx * s.centre.z,
                             camera.f * r1.y + camera.cy * r1.z, camera.f * r2.y + camera.cy * r2.z,
                             camera.f * s.centre.y + camera.cy * s.centre.z, r1.z, r2.z,
                             s.centre.z}};
  s.pixel_to_plane = inverse(plane_to_pixel);
  return true;
}

void draw(const PlacedSquare& s, std::vector<double>& image, uint32_t width) {
  for (int v = s.box.v0; v <= s.box.v1; ++v) {
    for (int u = s.box.u0; u <= s.box.u1; ++u) {
      double sum = 0.0;
      int inside = 0;
      for (int j = 0; j < kSamples; ++j) {
        for (int i = 0; i < kSamples; ++i) {
          double shade = 0.0;
          if (s.sample(u + (i + 0.5) / kSamples - 0.5, v + (j + 0.5) / kSamples - 0.5, shade)) {
            sum += shade;
            ++inside;
          }
        }
      }
      double& pixel = image[static_cast<std::size_t>(v) * width + static_cast<std::size_t>(u)];
      pixel = (sum + (kSamples * kSamples - inside) * pixel) / (kSamples * kSamples);
    }
  }
}

// A bar (a pole, a cable) in front of part of a tag; returns the fraction of the tag left visible.
double draw_occluder(const PlacedSquare& s, Random& random, std::vector<double>& image,
                     uint32_t width) {
  const double size = std::max(s.box.u1 - s.box.u0, s.box.v1 - s.box.v0);
  const auto [sin_a, cos_a] = portable_sin_cos(random.uniform(-3.14159, 3.14159));
  const double cu = 0.5 * (s.box.u0 + s.box.u1) + random.uniform(-0.25, 0.25) * size;
  const double cv = 0.5 * (s.box.v0 + s.box.v1) + random.uniform(-0.25, 0.25) * size;
  const double half_width = random.uniform(0.08, 0.2) * size;
  const double grey = random.uniform(70.0, 170.0);
  // Within the tag's own bounding box, which no other square's reaches: the bar hides only
  // this tag.
  const int u0 = s.box.u0;
  const int v0 = s.box.v0;
  const int u1 = s.box.u1;
  const int v1 = s.box.v1;
  long tag_samples = 0;
  long hidden_samples = 0;
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      int covered = 0;
      for (int j = 0; j < kSamples; ++j) {
        for (int i = 0; i < kSamples; ++i) {
          const double su = u + (i + 0.5) / kSamples - 0.5;
          const double sv = v + (j + 0.5) / kSamples - 0.5;
          const double across = (su - cu) * cos_a + (sv - cv) * sin_a;
          const bool hidden = across > -half_width && across < half_width;
          double shade = 0.0;
          if (s.sample(su, sv, shade)) {
            ++tag_samples;
            hidden_samples += hidden ? 1 : 0;
          }
          covered += hidden ? 1 : 0;
        }
      }
      double& pixel = image[static_cast<std::size_t>(v) * width + static_cast<std::size_t>(u)];
      pixel = (covered * grey + (kSamples * kSamples - covered) * pixel) / (kSamples * kSamples);
    }
  }
  return tag_samples == 0 ? 1.0 : 1.0 - static_cast<double>(hidden_samples) / tag_samples;
}

// Separable [1 2 1] / 4 blur (sigma about 0.7 px, the optics' softness), edges clamped.
void blur(std::vector<double>& image, uint32_t width, uint32_t height) {
  std::vector<double> tmp(image.size());
  for (uint32_t v = 0; v < height; ++v) {
    const double* row = &image[static_cast<std::size_t>(v) * width];
    double* out = &tmp[static_cast<std::size_t>(v) * width];
    for (uint32_t u = 0; u < width; ++u) {
      const double left = row[u == 0 ? 0 : u - 1];
      const double right = row[u + 1 == width ? u : u + 1];
      out[u] = 0.25 * left + 0.5 * row[u] + 0.25 * right;
    }
  }
  for (uint32_t v = 0; v < height; ++v) {
    const double* up = &tmp[static_cast<std::size_t>(v == 0 ? 0 : v - 1) * width];
    const double* mid = &tmp[static_cast<std::size_t>(v) * width];
    const double* down = &tmp[static_cast<std::size_t>(v + 1 == height ? v : v + 1) * width];
    double* out = &image[static_cast<std::size_t>(v) * width];
    for (uint32_t u = 0; u < width; ++u) out[u] = 0.25 * up[u] + 0.5 * mid[u] + 0.25 * down[u];
  }
}

Camera camera_of(const SyntheticAprilTagConfig& config, const msgs::CameraInfo& info) {
  return {info.k[0], info.k[2], info.k[5], config.width, config.height};
}

// The wall behind the tags: smooth shading and texture, in image space.
std::vector<double> wall(uint32_t w, uint32_t h, uint32_t seed) {
  std::vector<double> image(static_cast<std::size_t>(w) * h);
  for (uint32_t v = 0; v < h; ++v) {
    for (uint32_t u = 0; u < w; ++u) {
      image[static_cast<std::size_t>(v) * w + u] =
          135.0 + 45.0 * perception::raycast::value_noise(u / 90.0, v / 90.0, seed) +
          20.0 * perception::raycast::value_noise(u / 11.0, v / 11.0, seed + 1);
    }
  }
  return image;
}

// Draws the squares (then the occluders of those marked), blurs, adds noise, and writes the truth.
AprilTagFrame finish_frame(const SyntheticAprilTagConfig& config, const msgs::CameraInfo& info,
                           uint32_t k, std::vector<PlacedSquare>& placed,
                           const std::vector<bool>& occluded, Random& random) {
  const Camera camera = camera_of(config, info);
  const uint32_t w = config.width;
  const uint32_t h = config.height;
  std::vector<double> image = wall(w, h, static_cast<uint32_t>(random.next()));
  for (const PlacedSquare& s : placed) draw(s, image, w);
  for (std::size_t i = 0; i < placed.size(); ++i) {
    if (occluded[i]) placed[i].visible = draw_occluder(placed[i], random, image, w);
  }
  blur(image, w, h);

  AprilTagFrame frame;
  const auto stamp_ns = static_cast<int64_t>(std::llround(k * (1e9 / config.rate_hz)));
  msgs::Header header;
  header.stamp = msgs::Time::from_ns(stamp_ns);
  header.frame_id = config.frame_id;
  frame.info = info;
  frame.info.header = header;
  frame.image.header = header;
  frame.image.width = w;
  frame.image.height = h;
  frame.image.encoding = "rgb8";
  frame.image.step = 3 * w;
  frame.image.data.resize(static_cast<std::size_t>(3) * w * h);
  for (std::size_t i = 0; i < image.size(); ++i) {
    const double value = std::round(image[i] + config.noise_sigma * random.normal());
    const auto byte = static_cast<uint8_t>(std::clamp(value, 0.0, 255.0));
    frame.image.data[3 * i] = frame.image.data[3 * i + 1] = frame.image.data[3 * i + 2] = byte;
  }

  frame.tags.header = header;
  frame.poses.header = header;
  const double half = 0.5 * config.tag_size_m;
  for (const PlacedSquare& s : placed) {
    if (s.id < 0) continue;
    msgs::AprilTagDetection d;
    d.family = "36h11";
    d.id = s.id;
    d.goodness = static_cast<float>(s.visible);
    const Vec3 c = s.point(0.0, 0.0);
    d.centre = {camera.u(c), camera.v(c)};
    // libapriltag's order: its tag frame has y down, and corner i is (-1, 1), (1, 1), (1, -1),
    // (-1, -1) there.
    const std::pair<double, double> corners[4] = {
        {-half, -half}, {half, -half}, {half, half}, {-half, half}};
    for (int i = 0; i < 4; ++i) {
      const Vec3 p = s.point(corners[i].first, corners[i].second);
      d.corners[static_cast<std::size_t>(i)] = {camera.u(p), camera.v(p)};
    }
    // (-1..1 square, y down) -> pixels, scaled to H[8] = 1.
    const Mat3 plane_to_pixel = inverse(s.pixel_to_plane);
    const double scale[3] = {half, -half, 1.0};
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) {
        d.homography[static_cast<std::size_t>(3 * r + col)] =
            plane_to_pixel(r, col) * scale[col] / plane_to_pixel(2, 2);
      }
    }
    frame.tags.detections.push_back(std::move(d));
    msgs::Pose pose;
    pose.position = {s.centre.x, s.centre.y, s.centre.z};
    pose.orientation = quaternion_from_matrix(s.rotation);
    frame.poses.poses.push_back(pose);
  }
  return frame;
}

void set_contrast(PlacedSquare& s, Random& random) {
  s.dark = 25.0 + random.uniform(0.0, 20.0);
  s.light = s.dark + random.uniform(0.6, 1.0) * (225.0 - s.dark);
}

AprilTagFrame random_frame(const SyntheticAprilTagConfig& config, apriltag_family_t* family,
                           const msgs::CameraInfo& info, uint32_t k) {
  Random random(config.seed * 0x100000001b3ULL + k);
  const Camera camera = camera_of(config, info);
  const uint32_t wanted = config.tags_per_frame[k % config.tags_per_frame.size()];
  // More tags fit only farther away.
  const double near = std::min(config.min_distance_m * std::sqrt(std::max(1.0, wanted / 8.0)),
                               0.8 * config.max_distance_m);
  // Facing the camera: x right, y up, z towards it.
  const Mat3 facing{{1, 0, 0, 0, -1, 0, 0, 0, -1}};
  std::vector<PlacedSquare> placed;
  const uint32_t distractors = 3 + static_cast<uint32_t>(random.next() % 4);
  uint32_t tags = 0;
  uint32_t fakes = 0;
  for (int attempt = 0; attempt < 40000 && (tags < wanted || fakes < distractors); ++attempt) {
    const bool fake = fakes < distractors && (tags >= wanted || random.uniform() < 0.1);
    PlacedSquare s;
    s.cell = config.tag_size_m / kBorderCells;
    const double z = random.uniform(near, config.max_distance_m);
    const double u = random.uniform(0.0, config.width);
    const double v = random.uniform(0.0, config.height);
    s.centre = {(u - camera.cx) / camera.f * z, (v - camera.cy) / camera.f * z, z};
    const double tilt_x = random.uniform(-config.max_tilt_rad, config.max_tilt_rad);
    const double tilt_y = random.uniform(-config.max_tilt_rad, config.max_tilt_rad);
    s.rotation = facing * rotation(2, random.uniform(-3.14159, 3.14159)) * rotation(0, tilt_x) *
                 rotation(1, tilt_y);
    // Seen at most 60 degrees off its normal.
    const Vec3 normal = s.rotation.column(2);
    const double to_camera = -perception::raycast::dot(normal, s.centre);
    if (to_camera < 0.5 * std::sqrt(perception::raycast::dot(s.centre, s.centre))) continue;
    set_contrast(s, random);
    if (fake) {
      s.bits = distractor_bitmap(random);
    } else {
      // Ids distinct within a frame.
      do {
        s.id = static_cast<int>(random.next() % family->ncodes);
      } while (std::any_of(placed.begin(), placed.end(),
                           [&](const PlacedSquare& p) { return p.id == s.id; }));
      s.bits = tag_bitmap(family, s.id);
    }
    if (!place(s, camera, placed)) continue;
    (fake ? fakes : tags) += 1;
    placed.push_back(std::move(s));
  }
  std::vector<bool> occluded(placed.size());
  for (std::size_t i = 0; i < placed.size(); ++i) {
    occluded[i] = placed[i].id >= 0 && random.uniform() < config.occluded_fraction;
  }
  return finish_frame(config, info, k, placed, occluded, random);
}

msgs::CameraInfo camera_info(const SyntheticAprilTagConfig& config) {
  if (!(config.rate_hz > 0.0)) throw std::invalid_argument("apriltag sequence: rate must be > 0");
  if (!(config.tag_size_m > 0.0))
    throw std::invalid_argument("apriltag sequence: tag size must be > 0");
  if (!(config.min_distance_m > 0.0 && config.max_distance_m > config.min_distance_m)) {
    throw std::invalid_argument("apriltag sequence: need 0 < min_distance_m < max_distance_m");
  }
  if (config.tags_per_frame.empty())
    throw std::invalid_argument("apriltag sequence: tags_per_frame is empty");
  return perception::make_pinhole_camera_info(config.width, config.height, config.hfov_rad,
                                              std::vector<double>(5, 0.0), config.frame_id);
}

}  // namespace

std::vector<AprilTagFrame> generate_apriltag_sequence(const SyntheticAprilTagConfig& config) {
  const msgs::CameraInfo info = camera_info(config);
  const Family family(tag36h11_create());
  std::vector<AprilTagFrame> frames(config.frames);
  const uint32_t workers =
      std::max(1U, std::min(config.frames, std::thread::hardware_concurrency()));
  std::vector<std::thread> threads;
  for (uint32_t t = 0; t < workers; ++t) {
    threads.emplace_back([&, t] {
      for (uint32_t k = t; k < config.frames; k += workers) {
        frames[k] = random_frame(config, family.get(), info, k);
      }
    });
  }
  for (auto& thread : threads) thread.join();
  return frames;
}

AprilTagFrame render_apriltag_frame(const SyntheticAprilTagConfig& config,
                                    const std::vector<TagPlacement>& tags, uint32_t k) {
  const msgs::CameraInfo info = camera_info(config);
  const Camera camera = camera_of(config, info);
  const Family family(tag36h11_create());
  Random random(config.seed * 0x100000001b3ULL + k);
  std::vector<PlacedSquare> placed;
  for (const TagPlacement& t : tags) {
    if (t.id < 0 || static_cast<uint32_t>(t.id) >= family->ncodes)
      throw std::invalid_argument("apriltag frame: no tag36h11 id " + std::to_string(t.id));
    PlacedSquare s;
    s.id = t.id;
    s.bits = tag_bitmap(family.get(), t.id);
    s.cell = config.tag_size_m / kBorderCells;
    s.centre = {t.pose.position.x, t.pose.position.y, t.pose.position.z};
    const msgs::Quaternion& q = t.pose.orientation;
    s.rotation = {{1 - 2 * (q.y * q.y + q.z * q.z), 2 * (q.x * q.y - q.z * q.w),
                   2 * (q.x * q.z + q.y * q.w), 2 * (q.x * q.y + q.z * q.w),
                   1 - 2 * (q.x * q.x + q.z * q.z), 2 * (q.y * q.z - q.x * q.w),
                   2 * (q.x * q.z - q.y * q.w), 2 * (q.y * q.z + q.x * q.w),
                   1 - 2 * (q.x * q.x + q.y * q.y)}};
    set_contrast(s, random);
    if (!place(s, camera, placed)) {
      throw std::invalid_argument("apriltag frame: tag " + std::to_string(t.id) +
                                  " is not wholly in view, or overlaps another");
    }
    placed.push_back(std::move(s));
  }
  return finish_frame(config, info, k, placed, std::vector<bool>(placed.size(), false), random);
}

}  // namespace robotperf::localization
