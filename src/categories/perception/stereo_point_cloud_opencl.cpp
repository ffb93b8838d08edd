// The stereo point cloud on the OpenCL device (opencl_device()), by a kernel of robotperf's own
// with reprojectImageTo3D's double operations (within one float ulp of the cpu's): the opencl
// backend of
// stereo_point_cloud_computations.hpp.
#include <opencv2/core/ocl.hpp>
#include <stdexcept>

#include "device_stage.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "stereo_point_cloud_computations.hpp"

namespace robotperf::perception {
namespace {

// One work item per point, with reprojectImageTo3D's double operations: Q times (u, v, d, 1)
// summed term by term from zero, scaled by the reciprocal of its w. Every byte of a point is
// written, so that the downloaded cloud is complete.
constexpr const char* kStereoCloudSource = R"CL(
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#pragma OPENCL FP_CONTRACT OFF
double row_times(__global const double* q, double u, double v, double d) {
  double s = 0.0;
  s += q[0] * u;
  s += q[1] * v;
  s += q[2] * d;
  s += q[3] * 1.0;
  return s;
}

__kernel void stereo_cloud(__global const uchar* disparity, int disparity_step,
                           int disparity_offset, __global const uchar* colour, int colour_step,
                           int colour_offset, __global uchar* cloud, int cloud_step,
                           int cloud_offset, int rows, int cols, __global const double* q,
                           double min_disparity, int point_step, int use_colour, int rgb_offset,
                           int red, int green, int blue, int colour_px) {
  const int u = get_global_id(0), v = get_global_id(1);
  if (u >= cols || v >= rows) return;
  const double d = *(__global const float*)(disparity + disparity_offset + v * disparity_step +
                                            u * 4);
  const double iw = 1. / row_times(q + 12, u, v, d);
  const float x = (float)(row_times(q, u, v, d) * iw);
  const float y = (float)(row_times(q + 4, u, v, d) * iw);
  float fz = (float)(row_times(q + 8, u, v, d) * iw);
  if (fabs(d - min_disparity) <= FLT_EPSILON) fz = 10000.0f;
  const int valid = fz != 10000.0f && !isinf(fz);
  const float nan = as_float(0x7fc00000u);
  __global uchar* point = cloud + cloud_offset + v * cloud_step + u * point_step;
  for (int b = 0; b < point_step; ++b) point[b] = 0;
  __global float* f = (__global float*)point;
  f[0] = valid ? x : nan;
  f[1] = valid ? y : nan;
  f[2] = valid ? fz : nan;
  if (use_colour) {
    __global const uchar* px = colour + colour_offset + v * colour_step + u * colour_px;
    point[rgb_offset] = px[blue];
    point[rgb_offset + 1] = px[green];
    point[rgb_offset + 2] = px[red];
  }
}
)CL";

// What is on the device is kept from one message to the next.
class OpenClStereoPointCloud final : public StereoPointCloudComputation {
 public:
  void points(const cv::Mat& disparity, const cv::Mat& left, const StereoCloudModel& model,
              msgs::PointCloud2& cloud) override {
    if (kernel_.empty()) {
      static const cv::ocl::ProgramSource source(kStereoCloudSource);
      if (!kernel_.create("stereo_cloud", source, cv::String()))
        throw std::runtime_error("stereo point cloud: the OpenCL kernel did not build");
    }
    {
      DeviceStage upload("upload",
                         disparity.total() * disparity.elemSize() + left.total() * left.elemSize(),
                         opencl_queue());
      disparity.copyTo(disparity_);
      // Without colour the kernel reads no pixel: the disparity stands in for the image.
      if (model.colour) left.copyTo(left_);
      cv::Mat(model.q).copyTo(q_);
    }
    cloud_.create(disparity.rows, static_cast<int>(cloud.row_step), CV_8UC1);
    {
      DeviceStage stage("compute", 0, opencl_queue());
      // reprojectImageTo3D's missing disparity: the image's smallest.
      double min_disparity = 0;
      cv::minMaxIdx(disparity_, &min_disparity, nullptr);
      const cv::UMat& colour = model.colour ? left_ : disparity_;
      kernel_.args(cv::ocl::KernelArg::ReadOnlyNoSize(disparity_),
                   cv::ocl::KernelArg::ReadOnlyNoSize(colour),
                   cv::ocl::KernelArg::WriteOnlyNoSize(cloud_), disparity.rows, disparity.cols,
                   cv::ocl::KernelArg::PtrReadOnly(q_), min_disparity, model.point_step,
                   static_cast<int>(model.colour), model.rgb_offset, model.red, model.green,
                   model.blue, model.colour_bytes);
      size_t global[2] = {static_cast<size_t>(disparity.cols), static_cast<size_t>(disparity.rows)};
      if (!kernel_.run(2, global, nullptr, true))
        throw std::runtime_error("stereo point cloud: the OpenCL kernel did not run");
    }
    cv::Mat out(disparity.rows, static_cast<int>(cloud.row_step), CV_8UC1, cloud.data.data());
    {
      DeviceStage download("download", cloud.data.size(), opencl_queue());
      cloud_.copyTo(out);
    }
    if (out.data != cloud.data.data())
      throw std::logic_error("stereo point cloud: the device's cloud has another size");
  }

 private:
  cv::UMat disparity_, left_, q_, cloud_;
  cv::ocl::Kernel kernel_;
};

}  // namespace

std::unique_ptr<StereoPointCloudComputation> make_opencl_stereo_point_cloud() {
  opencl_device();
  const cv::ocl::Device& device = cv::ocl::Device::getDefault();
  if (device.doubleFPConfig() == 0) {
    throw std::invalid_argument("stereo point cloud: the OpenCL device '" + device.name() +
                                "' has no double precision (cl_khr_fp64), in which the "
                                "reprojection computes");
  }
  return std::make_unique<OpenClStereoPointCloud>();
}

}  // namespace robotperf::perception
