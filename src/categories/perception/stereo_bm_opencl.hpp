// Private to the perception category: StereoBM on the OpenCL device (opencl_device()).
#pragma once

#include <opencv2/core.hpp>

#include "robotperf/perception/stereo_image_proc.hpp"

namespace robotperf::perception {

// OpenCV StereoBM's answer, fixed point (1/16 px, invalid = (min_disparity - 1) * 16), computed on
// the device: every call uploads the pair and downloads the disparity. Throws
// std::invalid_argument for SGBM or a negative min_disparity, std::runtime_error when the device
// fails.
void stereo_bm_opencl(const cv::Mat& left, const cv::Mat& right, const StereoParams& params,
                      cv::Mat& disparity16);

}  // namespace robotperf::perception
