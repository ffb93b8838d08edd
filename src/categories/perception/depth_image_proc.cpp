#include "robotperf/perception/depth_image_proc.hpp"

#include <stdexcept>
#include <string>

#include "colour_layout.hpp"
#include "depth_image_proc_computations.hpp"
#include "robotperf/perception/cuda_device.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/opencl_device.hpp"

namespace robotperf::perception {
namespace {

// As depth_image_proc takes it from image_geometry: the principal point in float, the focal
// lengths in double.
struct Pinhole {
  float cx, cy;
  double fx, fy;
};

// depth_image_proc's constant of x (or y): the depth unit, a float widened to double, over the
// focal length in double, then narrowed; a division in float is one ulp off for some lengths.
float unit_over(float unit, double focal_length) {
  return static_cast<float>(static_cast<double>(unit) / focal_length);
}

// The constants every backend computes a point with, and the colour layout.
XyzrgbModel xyzrgb_model(bool is_float, const Pinhole& model, double range_max,
                         const ColourLayout& layout) {
  XyzrgbModel m;
  m.metres = is_float;
  const float unit =
      is_float ? DepthTraits<float>::to_metres(1.0f) : DepthTraits<uint16_t>::to_metres(1);
  m.cx = model.cx;
  m.cy = model.cy;
  m.constant_x = unit_over(unit, model.fx);
  m.constant_y = unit_over(unit, model.fy);
  m.fill_invalid = range_max != 0.0;
  m.fill = is_float ? DepthTraits<float>::from_metres(range_max)
                    : static_cast<float>(DepthTraits<uint16_t>::from_metres(range_max));
  m.red = layout.red;
  m.green = layout.green;
  m.blue = layout.blue;
  m.colour_bytes = layout.step;
  return m;
}

}  // namespace

std::span<const PointCloudImplementation> point_cloud_implementations() {
  static const PointCloudImplementation table[] = {
      {"cpu", make_cpu_point_cloud},
      {"opencl", make_opencl_point_cloud, opencl_device},
      {"cuda", make_cuda_point_cloud, cuda_device}};
  return table;
}

PointCloudXyzrgbProcessor::PointCloudXyzrgbProcessor(std::string_view backend)
    : PointCloudXyzrgbProcessor(implementation_on(point_cloud_implementations(), backend)) {}

PointCloudXyzrgbProcessor::PointCloudXyzrgbProcessor(const PointCloudImplementation& backend)
    : computation_(backend.make()) {}

PointCloudXyzrgbProcessor::~PointCloudXyzrgbProcessor() = default;
PointCloudXyzrgbProcessor::PointCloudXyzrgbProcessor(PointCloudXyzrgbProcessor&&) noexcept =
    default;
PointCloudXyzrgbProcessor& PointCloudXyzrgbProcessor::operator=(
    PointCloudXyzrgbProcessor&&) noexcept = default;

void PointCloudXyzrgbProcessor::compute(const msgs::Image& depth, const msgs::Image& colour,
                                        const msgs::CameraInfo& info,
                                        const PointCloudXyzrgbParams& params,
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
  const ColourLayout layout = colour_layout(colour.encoding, "point_cloud_xyzrgb");
  if (colour.width == 0 || colour.height == 0) {
    throw std::invalid_argument("point_cloud_xyzrgb: the colour image is empty (" +
                                std::to_string(colour.width) + "x" + std::to_string(colour.height) +
                                ")");
  }
  const cv::Mat depth_view = image_view(depth);
  const cv::Mat colour_view = image_view(colour);

  Pinhole model{static_cast<float>(info.p[2]), static_cast<float>(info.p[6]), info.p[0], info.p[5]};
  if (colour.width != depth.width || colour.height != depth.height) {
    // The camera model belongs to the colour image: scaled to the depth image by a ratio in
    // float, as depth_image_proc scales it.
    const float ratio = static_cast<float>(depth.width) / static_cast<float>(colour.width);
    model = {static_cast<float>(info.p[2] * ratio), static_cast<float>(info.p[6] * ratio),
             info.p[0] * ratio, info.p[5] * ratio};
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
  computation_->xyzrgb(depth_view, colour_view,
                       xyzrgb_model(is_float, model, params.range_max, layout), cloud);
}

void point_cloud_xyzrgb(const msgs::Image& depth, const msgs::Image& colour,
                        const msgs::CameraInfo& info, const PointCloudXyzrgbParams& params,
                        msgs::PointCloud2& cloud, std::string_view backend) {
  PointCloudXyzrgbProcessor(backend).compute(depth, colour, info, params, cloud);
}

}  // namespace robotperf::perception
