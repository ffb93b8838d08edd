// The disparity on the host CPU, with OpenCV's StereoBM or StereoSGBM as stereo_image_proc
// configures them: the cpu backend of stereo_image_proc_computations.hpp.
#include <opencv2/calib3d.hpp>

#include "stereo_image_proc_computations.hpp"

namespace robotperf::perception {
namespace {

cv::Ptr<cv::StereoMatcher> make_matcher(const StereoParams& p) {
  cv::Ptr<cv::StereoMatcher> matcher;
  if (p.algorithm == StereoAlgorithm::kBlockMatching) {
    auto bm = cv::StereoBM::create(p.disparity_range, p.correlation_window_size);
    bm->setPreFilterSize(p.prefilter_size);
    bm->setPreFilterCap(p.prefilter_cap);
    bm->setTextureThreshold(p.texture_threshold);
    bm->setUniquenessRatio(p.uniqueness_ratio);
    matcher = bm;
  } else {
    matcher =
        cv::StereoSGBM::create(p.min_disparity, p.disparity_range, p.correlation_window_size, p.p1,
                               p.p2, p.disp12_max_diff, p.prefilter_cap, p.uniqueness_ratio,
                               p.speckle_size, p.speckle_range, p.sgbm_mode);
  }
  matcher->setMinDisparity(p.min_disparity);
  matcher->setNumDisparities(p.disparity_range);
  matcher->setBlockSize(p.correlation_window_size);
  matcher->setSpeckleWindowSize(p.speckle_size);
  matcher->setSpeckleRange(p.speckle_range);
  matcher->setDisp12MaxDiff(p.disp12_max_diff);
  return matcher;
}

class CpuDisparity final : public DisparityComputation {
 public:
  explicit CpuDisparity(const StereoParams& params) : matcher_(make_matcher(params)) {}

  cv::Mat disparity16(const msgs::Image& left, const msgs::Image& right,
                      const std::function<void()>& make_output) override {
    to_mono8(left, kLeftImage, left_mono_);
    to_mono8(right, kRightImage, right_mono_);
    matcher_->compute(left_mono_, right_mono_, disparity16_);
    make_output();
    return disparity16_;
  }

 private:
  cv::Ptr<cv::StereoMatcher> matcher_;
  cv::Mat left_mono_, right_mono_, disparity16_;
};

}  // namespace

std::unique_ptr<DisparityComputation> make_cpu_disparity(const StereoParams& params) {
  return std::make_unique<CpuDisparity>(params);
}

}  // namespace robotperf::perception
