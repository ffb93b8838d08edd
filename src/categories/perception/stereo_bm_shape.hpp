// Private to the perception category: StereoBM's sizes and thresholds for one image size and
// parameter set, as the device kernels of the opencl and cuda backends take them. Plain data,
// free of OpenCV, so that CUDA's device code can include it.
#pragma once

namespace robotperf::perception {

struct BlockMatchingShape {
  int rows = 0, cols = 0;
  int disparities = 0;  // disparity_range: the disparities searched
  // The right image's column offset, max(disparities - 1 + min_disparity, 0): cost index k of
  // left column c compares right column c - offset + k, disparity offset - k.
  int right_offset = 0;
  int radius = 0;  // half the correlation window
  int prefilter_cap = 0;
  int min_disparity = 0;
  int texture_threshold = 0;
  int uniqueness_ratio = 0;
  // The region where the window and the search range fit, [x0, x1) x [y0, y1), as OpenCV's
  // valid disparity ROI: every other pixel is filtered.
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
};

}  // namespace robotperf::perception
