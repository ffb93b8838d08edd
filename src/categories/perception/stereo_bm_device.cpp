#include "stereo_bm_device.hpp"

#include <algorithm>
#include <opencv2/calib3d.hpp>

namespace robotperf::perception {

BlockMatchingShape block_matching_shape(int rows, int cols, const StereoParams& p) {
  BlockMatchingShape s;
  s.rows = rows;
  s.cols = cols;
  s.disparities = p.disparity_range;
  s.right_offset = std::max(p.disparity_range - 1 + p.min_disparity, 0);
  s.radius = p.correlation_window_size / 2;
  s.prefilter_cap = p.prefilter_cap;
  s.min_disparity = p.min_disparity;
  s.texture_threshold = p.texture_threshold;
  s.uniqueness_ratio = p.uniqueness_ratio;
  s.x0 = p.min_disparity + p.disparity_range - 1 + s.radius;
  s.x1 = std::min(cols, cols + p.min_disparity) - s.radius;
  s.y0 = s.radius;
  s.y1 = rows - s.radius;
  return s;
}

void filter_on_host(cv::Mat& disparity16, const StereoParams& p) {
  if (p.speckle_size > 0 && p.speckle_range >= 0) {
    cv::filterSpeckles(disparity16, (p.min_disparity - 1) * 16, p.speckle_size, p.speckle_range);
  }
}

}  // namespace robotperf::perception
