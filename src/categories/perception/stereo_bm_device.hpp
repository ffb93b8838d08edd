// Private to the perception category: what the opencl and cuda backends' StereoBM share on the
// host, before and after the device's part.
#pragma once

#include <opencv2/core.hpp>

#include "robotperf/perception/stereo_image_proc.hpp"
#include "stereo_bm_shape.hpp"

namespace robotperf::perception {

// StereoBM's shape for a rows x cols pair under `params` (block matching, min_disparity >= 0).
BlockMatchingShape block_matching_shape(int rows, int cols, const StereoParams& params);

// StereoBM's step after the device's, on the downloaded fixed-point disparity in place, with
// OpenCV's own function: the speckle filter (connected components, sequential). StereoBM makes no
// left-right check (disp12_max_diff is StereoSGBM's).
void filter_on_host(cv::Mat& disparity16, const StereoParams& params);

}  // namespace robotperf::perception
