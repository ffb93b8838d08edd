// Private to the perception category: StereoBM on the OpenCL device (opencl_device()).
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/core/ocl.hpp>

#include "robotperf/perception/stereo_image_proc.hpp"

namespace robotperf::perception {

// OpenCV StereoBM's answer, fixed point (1/16 px, invalid = (min_disparity - 1) * 16), computed on
// the device: every call uploads the pair and downloads the disparity. The device's buffers (the
// cost volume is 80 MB for a 640x480 pair at 64 disparities) and kernels are kept from one pair to
// the next of the same size. compute() throws std::invalid_argument for SGBM, a negative
// min_disparity, or a cost volume larger than the device allocates at once
// (CL_DEVICE_MAX_MEM_ALLOC_SIZE), std::runtime_error when the device fails.
class OpenClBlockMatcher {
 public:
  void compute(const cv::Mat& left, const cv::Mat& right, const StereoParams& params,
               cv::Mat& disparity16);

 private:
  cv::UMat left_, right_, filtered_left_, filtered_right_, row_costs_, costs_, disparity_;
  cv::ocl::Kernel prefilter_, row_kernel_, window_kernel_, choose_;
};

}  // namespace robotperf::perception
