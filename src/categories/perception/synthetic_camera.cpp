#include "robotperf/perception/synthetic_camera.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/plugin/content_hash.hpp"

namespace robotperf::perception {
namespace {

// Everything is drawn with integer coordinates and the distortion is applied with OpenCV's
// fixed-point remap, so the bytes do not depend on the thread count or SIMD width.

constexpr int kNewtonIterations = 12;
constexpr double kNewtonTolerance = 1e-9;

struct PlumbBob {
  double fx, fy, cx, cy;
  double k1, k2, p1, p2, k3;

  // Forward model on normalised coordinates, with its Jacobian.
  void distort(double x, double y, double& xd, double& yd, cv::Matx22d& jacobian) const {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    // d(radial)/dx = x * radial_slope, d(radial)/dy = y * radial_slope.
    const double radial_slope = 2.0 * k1 + r2 * (4.0 * k2 + r2 * 6.0 * k3);
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    jacobian = cv::Matx22d(radial + radial_slope * x * x + 2.0 * p1 * y + 6.0 * p2 * x,
                           radial_slope * x * y + 2.0 * p1 * x + 2.0 * p2 * y,
                           radial_slope * x * y + 2.0 * p1 * x + 2.0 * p2 * y,
                           radial + radial_slope * y * y + 6.0 * p1 * y + 2.0 * p2 * x);
  }

  // The ideal pixel a raw pixel sees (inverse model, Newton's method); false if it does not
  // converge.
  bool undistort_pixel(double u, double v, cv::Point2d& ideal) const {
    const double xd = (u - cx) / fx;
    const double yd = (v - cy) / fy;
    double x = xd;
    double y = yd;
    double residual = 0.0;
    for (int i = 0; i < kNewtonIterations; ++i) {
      double fxd = 0.0;
      double fyd = 0.0;
      cv::Matx22d jacobian;
      distort(x, y, fxd, fyd, jacobian);
      const double ex = fxd - xd;
      const double ey = fyd - yd;
      residual = std::abs(ex) + std::abs(ey);
      const double det = jacobian(0, 0) * jacobian(1, 1) - jacobian(0, 1) * jacobian(1, 0);
      if (det == 0.0) return false;
      x -= (jacobian(1, 1) * ex - jacobian(0, 1) * ey) / det;
      y -= (jacobian(0, 0) * ey - jacobian(1, 0) * ex) / det;
    }
    ideal = cv::Point2d(fx * x + cx, fy * y + cy);
    return residual < kNewtonTolerance;
  }
};

int floor_div(int a, int b) {
  return a / b - ((a % b != 0) && ((a < 0) != (b < 0)));
}

uint32_t mix_bits(uint32_t h) {
  h ^= h >> 16;
  h *= 0x85ebca6bU;
  h ^= h >> 13;
  h *= 0xc2b2ae35U;
  h ^= h >> 16;
  return h;
}

// The scene for one configuration: checkerboard background and the lens's distortion map, both
// on a canvas that extends the ideal image by `margin` pixels on each side so that every raw
// pixel (a barrel lens sees beyond the ideal frame) lands on scene content.
class SceneRenderer {
 public:
  explicit SceneRenderer(const SyntheticCameraConfig& config) : config_(config) {
    const msgs::CameraInfo info = perception::make_pinhole_camera_info(
        config.width, config.height, config.hfov_rad, config.distortion, config.frame_id);
    const std::vector<double>& d = config.distortion;
    const PlumbBob lens{info.k[0], info.k[4], info.k[2],
                        info.k[5], d[0],      d[1],
                        d[2],      d[3],      d.size() > 4 ? d[4] : 0.0};

    const int width = static_cast<int>(config.width);
    const int height = static_cast<int>(config.height);
    std::vector<cv::Point2d> ideal(static_cast<size_t>(width) * height);
    std::vector<uint8_t> converged(ideal.size());
    double overshoot = 0.0;
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        const size_t i = static_cast<size_t>(v) * width + u;
        converged[i] = lens.undistort_pixel(u, v, ideal[i]);
        if (converged[i]) {
          overshoot = std::max({overshoot, -ideal[i].x, -ideal[i].y, ideal[i].x - (width - 1),
                                ideal[i].y - (height - 1)});
        }
      }
    }
    margin_ = static_cast<int>(std::ceil(overshoot)) + 2;

    // Pixels whose inverse did not converge map far outside the canvas: border (black).
    constexpr float kOutside = -1e4f;
    cv::Mat map(height, width, CV_32FC2);
    for (int v = 0; v < height; ++v) {
      auto* row = map.ptr<cv::Vec2f>(v);
      for (int u = 0; u < width; ++u) {
        const size_t i = static_cast<size_t>(v) * width + u;
        row[u] = converged[i] ? cv::Vec2f(static_cast<float>(ideal[i].x + margin_),
                                          static_cast<float>(ideal[i].y + margin_))
                              : cv::Vec2f(kOutside, kOutside);
      }
    }
    cv::convertMaps(map, cv::noArray(), distort_map_xy_, distort_map_fraction_, CV_16SC2);

    background_.create(height + 2 * margin_, width + 2 * margin_, CV_8UC3);
    for (int y = 0; y < background_.rows; ++y) {
      auto* row = background_.ptr<cv::Vec3b>(y);
      const int tile_y = floor_div(y - margin_, kCheckerTilePx);
      for (int x = 0; x < background_.cols; ++x) {
        const int tile_x = floor_div(x - margin_, kCheckerTilePx);
        row[x] = tile_colour(tile_x, tile_y);
      }
    }
  }

  // The ideal image of frame `index` on the canvas.
  void render_canvas(uint32_t index, cv::Mat& canvas) const {
    background_.copyTo(canvas);
    const int width = static_cast<int>(config_.width);
    const int height = static_cast<int>(config_.height);
    // A box about a fifth of the image wide travelling from the left edge to the right one,
    // drifting down a little.
    const int box_width = std::max(width * 3 / 16, 4);
    const int box_height = std::max(height * 3 / 16, 4);
    const int64_t steps = std::max<int64_t>(int64_t{config_.frames} - 1, 1);
    const int64_t travel_x = std::max(width * 7 / 8 - box_width, 0);
    const int x = width / 16 + static_cast<int>(index * travel_x / steps);
    const int y = height * 3 / 8 + static_cast<int>(index * int64_t{height / 8} / steps);
    const cv::Rect box(x + margin_, y + margin_, box_width, box_height);
    cv::rectangle(canvas, box, cv::Scalar(40, 90, 200), cv::FILLED, cv::LINE_8);
    cv::line(canvas, box.tl(), box.br() - cv::Point(1, 1), cv::Scalar(250, 250, 250), 2,
             cv::LINE_8);
    cv::line(canvas, cv::Point(box.x + box.width - 1, box.y),
             cv::Point(box.x, box.y + box.height - 1), cv::Scalar(250, 250, 250), 2, cv::LINE_8);
    cv::rectangle(canvas, box, cv::Scalar(15, 15, 15), 3, cv::LINE_8);
  }

  void render_ideal(uint32_t index, cv::Mat& image) const {
    cv::Mat canvas;
    render_canvas(index, canvas);
    canvas(cv::Rect(margin_, margin_, static_cast<int>(config_.width),
                    static_cast<int>(config_.height)))
        .copyTo(image);
  }

  void render_raw(uint32_t index, cv::Mat& canvas, cv::Mat& raw) const {
    render_canvas(index, canvas);
    cv::remap(canvas, raw, distort_map_xy_, distort_map_fraction_, cv::INTER_LINEAR,
              cv::BORDER_CONSTANT, cv::Scalar::all(0));
  }

 private:
  // Bright and dark tiles alternate; each tile's colour varies a little so that rgb matters.
  static cv::Vec3b tile_colour(int tile_x, int tile_y) {
    const uint32_t h = mix_bits(static_cast<uint32_t>(tile_x) * 73856093U ^
                                static_cast<uint32_t>(tile_y) * 19349663U);
    const bool bright = ((tile_x + tile_y) & 1) == 0;
    const int base = bright ? 195 : 25;
    return cv::Vec3b(static_cast<uint8_t>(base + (h & 0x1f)),
                     static_cast<uint8_t>(base + ((h >> 8) & 0x1f)),
                     static_cast<uint8_t>(base + ((h >> 16) & 0x1f)));
  }

  const SyntheticCameraConfig& config_;
  int margin_ = 0;
  cv::Mat distort_map_xy_, distort_map_fraction_;
  cv::Mat background_;
};

void validate(const SyntheticCameraConfig& config) {
  if (config.width == 0 || config.height == 0 || config.width > 1u << 15 ||
      config.height > 1u << 15) {
    throw std::invalid_argument("synthetic camera size must be 1 .. 32768 pixels a side");
  }
  if (!(config.rate_hz > 0.0)) {
    throw std::invalid_argument("synthetic camera rate_hz must be positive");
  }
  if (config.distortion.size() != 4 && config.distortion.size() != 5) {
    throw std::invalid_argument("synthetic camera distortion must be plumb_bob k1 k2 p1 p2 [k3]");
  }
}

msgs::Header frame_header(const SyntheticCameraConfig& config, uint32_t index) {
  msgs::Header header;
  header.stamp = msgs::Time::from_ns(std::llround(index * 1e9 / config.rate_hz));
  header.frame_id = config.frame_id;
  return header;
}

void hash_header(plugin::Fnv1a64& hash, const msgs::Header& header) {
  hash.add_i32(header.stamp.sec).add_u32(header.stamp.nanosec).add_string(header.frame_id);
}

}  // namespace

std::vector<CameraFrame> generate_camera_sequence(const SyntheticCameraConfig& config) {
  validate(config);
  const SceneRenderer scene(config);
  const msgs::CameraInfo info = perception::make_pinhole_camera_info(
      config.width, config.height, config.hfov_rad, config.distortion, config.frame_id);
  std::vector<CameraFrame> frames(config.frames);
  cv::Mat canvas;
  for (uint32_t k = 0; k < config.frames; ++k) {
    CameraFrame& frame = frames[k];
    const msgs::Header header = frame_header(config, k);
    cv::Mat raw =
        perception::prepare_image(frame.image, header, "rgb8", static_cast<int>(config.width),
                                  static_cast<int>(config.height));
    scene.render_raw(k, canvas, raw);
    frame.info = info;
    frame.info.header = header;
  }
  return frames;
}

msgs::Image render_ideal_camera_frame(const SyntheticCameraConfig& config, uint32_t index) {
  validate(config);
  const SceneRenderer scene(config);
  msgs::Image image;
  cv::Mat view =
      perception::prepare_image(image, frame_header(config, index), "rgb8",
                                static_cast<int>(config.width), static_cast<int>(config.height));
  scene.render_ideal(index, view);
  return image;
}

std::string camera_sequence_hash(const std::vector<CameraFrame>& frames) {
  plugin::Fnv1a64 hash;
  hash.add_u64(frames.size());
  for (const CameraFrame& frame : frames) {
    const msgs::Image& image = frame.image;
    hash_header(hash, image.header);
    hash.add_u32(image.height).add_u32(image.width).add_string(image.encoding);
    hash.add_u8(image.is_bigendian).add_u32(image.step).add_bytes(image.data);

    const msgs::CameraInfo& info = frame.info;
    hash_header(hash, info.header);
    hash.add_u32(info.height).add_u32(info.width).add_string(info.distortion_model);
    hash.add_u64(info.d.size());
    for (const double c : info.d) hash.add_f64(c);
    for (const double c : info.k) hash.add_f64(c);
    for (const double c : info.r) hash.add_f64(c);
    for (const double c : info.p) hash.add_f64(c);
    hash.add_u32(info.binning_x).add_u32(info.binning_y);
    hash.add_u32(info.roi.x_offset).add_u32(info.roi.y_offset);
    hash.add_u32(info.roi.height).add_u32(info.roi.width).add_u8(info.roi.do_rectify ? 1 : 0);
  }
  return hash.hex_digest();
}

}  // namespace robotperf::perception
