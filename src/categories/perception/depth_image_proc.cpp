#include "robotperf/perception/depth_image_proc.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "robotperf/perception/image_proc.hpp"

namespace robotperf::perception {
namespace {

struct ColourLayout {
  int red, green, blue, step;
};

ColourLayout colour_layout(const std::string& encoding) {
  if (encoding == "rgb8") return {0, 1, 2, 3};
  if (encoding == "rgba8") return {0, 1, 2, 4};
  if (encoding == "bgr8") return {2, 1, 0, 3};
  if (encoding == "bgra8") return {2, 1, 0, 4};
  if (encoding == "mono8") return {0, 0, 0, 1};
  throw std::invalid_argument("point_cloud_xyzrgb: colour encoding '" + encoding +
                              "' is not supported (rgb8, rgba8, bgr8, bgra8, mono8)");
}

// Depth in the image's own unit: metres for float, millimetres for uint16.
template <class T>
struct DepthTraits;
template <>
struct DepthTraits<float> {
  static bool valid(float d) { return std::isfinite(d); }
  static float to_metres(float d) { return d; }
  static float from_metres(double m) { return static_cast<float>(m); }
};
template <>
struct DepthTraits<uint16_t> {
  static bool valid(uint16_t d) { return d != 0; }
  static float to_metres(uint16_t d) { return d * 0.001f; }
  static uint16_t from_metres(double m) { return static_cast<uint16_t>(m * 1000.0); }
};

struct Pinhole {
  float cx, cy, fx, fy;
};

template <class T>
void convert_depth(const cv::Mat& depth, const Pinhole& model, double range_max,
                   msgs::PointCloud2& cloud) {
  using Traits = DepthTraits<T>;
  const float unit = Traits::to_metres(T(1));
  const float constant_x = unit / model.fx;
  const float constant_y = unit / model.fy;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const bool fill_invalid = range_max != 0.0;
  const T fill = Traits::from_metres(range_max);
  uint8_t* out = cloud.data.data();
  for (int v = 0; v < depth.rows; ++v) {
    const T* row = depth.ptr<T>(v);
    for (int u = 0; u < depth.cols; ++u, out += kXyzrgbPointStep) {
      T d = row[u];
      float xyz[3];
      if (!Traits::valid(d) && !fill_invalid) {
        xyz[0] = xyz[1] = xyz[2] = nan;
      } else {
        if (!Traits::valid(d)) d = fill;
        xyz[0] = (static_cast<float>(u) - model.cx) * d * constant_x;
        xyz[1] = (static_cast<float>(v) - model.cy) * d * constant_y;
        xyz[2] = Traits::to_metres(d);
      }
      std::memcpy(out + kXyzrgbOffsetX, xyz, sizeof xyz);
    }
  }
}

void convert_colour(const cv::Mat& colour, const ColourLayout& layout, msgs::PointCloud2& cloud) {
  uint8_t* out = cloud.data.data() + kXyzrgbOffsetRgb;
  for (int v = 0; v < colour.rows; ++v) {
    const uint8_t* px = colour.ptr<uint8_t>(v);
    for (int u = 0; u < colour.cols; ++u, px += layout.step, out += kXyzrgbPointStep) {
      // Packed as PointCloud2Iterator's "b", "g", "r" views of the rgb field place them.
      out[0] = px[layout.blue];
      out[1] = px[layout.green];
      out[2] = px[layout.red];
    }
  }
}

}  // namespace

void point_cloud_xyzrgb(const msgs::Image& depth, const msgs::Image& colour,
                        const msgs::CameraInfo& info, const PointCloudXyzrgbParams& params,
                        msgs::PointCloud2& cloud) {
  if (depth.header.frame_id != colour.header.frame_id) {
    throw std::invalid_argument("point_cloud_xyzrgb: depth frame '" + depth.header.frame_id +
                                "' differs from colour frame '" + colour.header.frame_id +
                                "' (the depth image must be registered to the colour camera)");
  }
  if (info.p[0] == 0.0 || info.p[5] == 0.0) {
    throw std::invalid_argument("point_cloud_xyzrgb: CameraInfo has no focal length (P[0], P[5])");
  }
  if (!(params.range_max >= 0.0)) {
    throw std::invalid_argument("point_cloud_xyzrgb: range_max must be >= 0");
  }
  const bool is_float = depth.encoding == "32FC1";
  if (!is_float && depth.encoding != "16UC1" && depth.encoding != "mono16") {
    throw std::invalid_argument("point_cloud_xyzrgb: depth encoding '" + depth.encoding +
                                "' is not supported (32FC1 metres, 16UC1 millimetres)");
  }
  const ColourLayout layout = colour_layout(colour.encoding);
  const cv::Mat depth_view = image_view(depth);
  cv::Mat colour_view = image_view(colour);

  Pinhole model{static_cast<float>(info.p[2]), static_cast<float>(info.p[6]),
                static_cast<float>(info.p[0]), static_cast<float>(info.p[5])};
  if (colour.width != depth.width || colour.height != depth.height) {
    // The camera model belongs to the colour image: scale it to the depth image.
    const double ratio = static_cast<double>(depth.width) / colour.width;
    model = {static_cast<float>(info.p[2] * ratio), static_cast<float>(info.p[6] * ratio),
             static_cast<float>(info.p[0] * ratio), static_cast<float>(info.p[5] * ratio)};
    cv::Mat resized;
    cv::resize(colour_view, resized, depth_view.size(), 0, 0, cv::INTER_LINEAR);
    colour_view = resized;
  }

  cloud.header = depth.header;
  cloud.height = depth.height;
  cloud.width = depth.width;
  cloud.is_bigendian = false;
  cloud.is_dense = false;
  cloud.point_step = kXyzrgbPointStep;
  cloud.row_step = kXyzrgbPointStep * depth.width;
  constexpr uint8_t kFloat32 = msgs::PointField::kFloat32;
  cloud.fields = {{"x", kXyzrgbOffsetX, kFloat32, 1},
                  {"y", kXyzrgbOffsetY, kFloat32, 1},
                  {"z", kXyzrgbOffsetZ, kFloat32, 1},
                  {"rgb", kXyzrgbOffsetRgb, kFloat32, 1}};
  // Every point's x, y, z and b, g, r bytes are written below; padding and the fourth rgb byte
  // are zero from the allocation, so a cloud of the same size is reused without clearing.
  const std::size_t bytes = static_cast<std::size_t>(cloud.row_step) * depth.height;
  if (cloud.data.size() != bytes) cloud.data.assign(bytes, 0);
  if (depth_view.empty()) return;
  if (is_float) {
    convert_depth<float>(depth_view, model, params.range_max, cloud);
  } else {
    convert_depth<uint16_t>(depth_view, model, params.range_max, cloud);
  }
  convert_colour(colour_view, layout, cloud);
}

}  // namespace robotperf::perception
