// The point cloud on the OpenCL device (opencl_device()), by a kernel of robotperf's own with the
// cpu's float operations: the opencl backend of depth_image_proc_computations.hpp.
#include <opencv2/core/ocl.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "depth_image_proc_computations.hpp"
#include "device_stage.hpp"
#include "robotperf/perception/opencl_device.hpp"

namespace robotperf::perception {
namespace {

// The images on the device (OpenCV's transparent API), and the kernel, built at the first message.
struct OpenClCloudBuffers {
  cv::UMat depth, colour, resized_colour, cloud;
  cv::ocl::Kernel xyzrgb;
};

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

// What is on the device is kept from one message to the next.
class OpenClPointCloud final : public PointCloudComputation {
 public:
  void xyzrgb(const cv::Mat& depth, const cv::Mat& colour, const XyzrgbModel& model,
              msgs::PointCloud2& cloud) override {
    convert_on_opencl(depth, colour, model, device_, cloud);
  }

 private:
  OpenClCloudBuffers device_;
};

}  // namespace

std::unique_ptr<PointCloudComputation> make_opencl_point_cloud() {
  opencl_device();
  return std::make_unique<OpenClPointCloud>();
}

}  // namespace robotperf::perception
