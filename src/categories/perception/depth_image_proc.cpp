#include "robotperf/perception/depth_image_proc.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/core/ocl.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "cuda/cuda_backend.hpp"
#include "device_stage.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "xyzrgb_model.hpp"

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
  // Rounded to the nearest millimetre in float, as depth_image_proc's fromMeters (2.01 m is 2010,
  // not 2009); a range beyond the encoding's 65.535 m saturates instead of wrapping.
  static uint16_t from_metres(double m) {
    return static_cast<uint16_t>(std::min(static_cast<float>(m) * 1000.0f + 0.5f, 65535.0f));
  }
};

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

template <class T>
void convert_depth(const cv::Mat& depth, const Pinhole& model, double range_max,
                   msgs::PointCloud2& cloud) {
  using Traits = DepthTraits<T>;
  const float unit = Traits::to_metres(T(1));
  const float constant_x = unit_over(unit, model.fx);
  const float constant_y = unit_over(unit, model.fy);
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

// The constants convert_depth computes with and the colour layout, for the device kernels.
XyzrgbModel device_model(bool is_float, const Pinhole& model, double range_max,
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

// The OpenCL twin of convert_depth and convert_colour: one work item per point, writing all of
// its 32 bytes (padding zero) so that the downloaded cloud is complete.
constexpr const char* kXyzrgbSource = R"CL(
#pragma OPENCL FP_CONTRACT OFF
__kernel void xyzrgb(__global const uchar* depth, int depth_step, int depth_offset,
                     __global const uchar* colour, int colour_step, int colour_offset,
                     __global uchar* cloud, int cloud_step, int cloud_offset,
                     int rows, int cols, int is_float, float cx, float cy, float constant_x,
                     float constant_y, int fill_invalid, float fill, int red, int green,
                     int blue, int colour_px) {
  const int u = get_global_id(0), v = get_global_id(1);
  if (u >= cols || v >= rows) return;
  float d;
  int valid;
  if (is_float) {
    d = *(__global const float*)(depth + depth_offset + v * depth_step + u * 4);
    valid = isfinite(d);
  } else {
    const ushort raw = *(__global const ushort*)(depth + depth_offset + v * depth_step + u * 2);
    d = (float)raw;
    valid = raw != 0;
  }
  float x, y, z;
  if (!valid && !fill_invalid) {
    x = y = z = as_float(0x7fc00000u);
  } else {
    if (!valid) d = fill;
    x = ((float)u - cx) * d * constant_x;
    y = ((float)v - cy) * d * constant_y;
    z = is_float ? d : d * 0.001f;
  }
  __global uchar* p = cloud + cloud_offset + v * cloud_step + u * 32;
  __global float* f = (__global float*)p;
  f[0] = x;
  f[1] = y;
  f[2] = z;
  f[3] = 0.0f;
  __global const uchar* px = colour + colour_offset + v * colour_step + u * colour_px;
  p[16] = px[blue];
  p[17] = px[green];
  p[18] = px[red];
  p[19] = 0;
  f[5] = f[6] = f[7] = 0.0f;
}
)CL";

void convert_on_opencl(const cv::Mat& depth, const cv::Mat& colour, const XyzrgbModel& m,
                       OpenClCloudBuffers& device, msgs::PointCloud2& cloud) {
  cv::ocl::Kernel& kernel = device.xyzrgb;
  if (kernel.empty()) {
    static const cv::ocl::ProgramSource source(kXyzrgbSource);
    if (!kernel.create("xyzrgb", source, cv::String()))
      throw std::runtime_error("point_cloud_xyzrgb: the OpenCL kernel did not build");
  }
  {
    DeviceStage upload("upload",
                       depth.total() * depth.elemSize() + colour.total() * colour.elemSize(),
                       opencl_queue());
    depth.copyTo(device.depth);
    colour.copyTo(device.colour);
  }
  device.cloud.create(depth.rows, static_cast<int>(cloud.row_step), CV_8UC1);
  {
    DeviceStage stage("compute", 0, opencl_queue());
    const cv::UMat* pixel_colours = &device.colour;
    if (device.colour.size() != device.depth.size()) {
      cv::resize(device.colour, device.resized_colour, device.depth.size(), 0, 0, cv::INTER_LINEAR);
      pixel_colours = &device.resized_colour;
    }
    kernel.args(cv::ocl::KernelArg::ReadOnlyNoSize(device.depth),
                cv::ocl::KernelArg::ReadOnlyNoSize(*pixel_colours),
                cv::ocl::KernelArg::WriteOnlyNoSize(device.cloud), depth.rows, depth.cols,
                static_cast<int>(m.metres), m.cx, m.cy, m.constant_x, m.constant_y,
                static_cast<int>(m.fill_invalid), m.fill, m.red, m.green, m.blue, m.colour_bytes);
    size_t global[2] = {static_cast<size_t>(depth.cols), static_cast<size_t>(depth.rows)};
    if (!kernel.run(2, global, nullptr, true))
      throw std::runtime_error("point_cloud_xyzrgb: the OpenCL kernel did not run");
  }
  cv::Mat out(depth.rows, static_cast<int>(cloud.row_step), CV_8UC1, cloud.data.data());
  {
    DeviceStage download("download", cloud.data.size(), opencl_queue());
    device.cloud.copyTo(out);
  }
  if (out.data != cloud.data.data())
    throw std::logic_error("point_cloud_xyzrgb: the device's cloud has another size");
}

}  // namespace

PointCloudXyzrgbProcessor::PointCloudXyzrgbProcessor(ImageBackend backend) : backend_(backend) {
  if (backend == ImageBackend::kOpenCl) opencl_device();
  if (backend == ImageBackend::kCuda) cuda_ = cuda::make_point_cloud_maker();
}

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
  const ColourLayout layout = colour_layout(colour.encoding);
  if (colour.width == 0 || colour.height == 0) {
    throw std::invalid_argument("point_cloud_xyzrgb: the colour image is empty (" +
                                std::to_string(colour.width) + "x" + std::to_string(colour.height) +
                                ")");
  }
  const cv::Mat depth_view = image_view(depth);
  cv::Mat colour_view = image_view(colour);

  Pinhole model{static_cast<float>(info.p[2]), static_cast<float>(info.p[6]), info.p[0], info.p[5]};
  if (colour.width != depth.width || colour.height != depth.height) {
    // The camera model belongs to the colour image: scaled to the depth image by a ratio in
    // float, as depth_image_proc scales it.
    const float ratio = static_cast<float>(depth.width) / static_cast<float>(colour.width);
    model = {static_cast<float>(info.p[2] * ratio), static_cast<float>(info.p[6] * ratio),
             info.p[0] * ratio, info.p[5] * ratio};
    if (backend_ == ImageBackend::kCpu) {
      cv::Mat resized;
      cv::resize(colour_view, resized, depth_view.size(), 0, 0, cv::INTER_LINEAR);
      colour_view = resized;
    }
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
  if (backend_ == ImageBackend::kOpenCl) {
    convert_on_opencl(depth_view, colour_view,
                      device_model(is_float, model, params.range_max, layout), opencl_, cloud);
    return;
  }
  if (backend_ == ImageBackend::kCuda) {
    cv::Mat points(depth_view.rows, static_cast<int>(cloud.row_step), CV_8UC1, cloud.data.data());
    cuda_->xyzrgb(depth_view, colour_view, device_model(is_float, model, params.range_max, layout),
                  points);
    return;
  }
  if (is_float) {
    convert_depth<float>(depth_view, model, params.range_max, cloud);
  } else {
    convert_depth<uint16_t>(depth_view, model, params.range_max, cloud);
  }
  convert_colour(colour_view, layout, cloud);
}

void point_cloud_xyzrgb(const msgs::Image& depth, const msgs::Image& colour,
                        const msgs::CameraInfo& info, const PointCloudXyzrgbParams& params,
                        msgs::PointCloud2& cloud, ImageBackend backend) {
  PointCloudXyzrgbProcessor(backend).compute(depth, colour, info, params, cloud);
}

}  // namespace robotperf::perception
