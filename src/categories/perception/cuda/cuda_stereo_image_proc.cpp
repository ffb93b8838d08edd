// The disparity on the CUDA device: the cuda backend of stereo_image_proc_computations.hpp, on
// the block matcher of cuda_backend.hpp (which, in a build without the toolkit, says so in one
// line when it is made). Compiled by the host compiler in every build.
#include "../stereo_image_proc_computations.hpp"
#include "cuda_backend.hpp"

namespace robotperf::perception {
namespace {

class CudaDisparity final : public DisparityComputation {
 public:
  explicit CudaDisparity(const StereoParams& params)
      : params_(params), matcher_(cuda::make_block_matcher(params)) {}

  // The pair is written into the device's upload memory, and the output message made while the
  // device works.
  cv::Mat disparity16(const msgs::Image& left, const msgs::Image& right,
                      const std::function<void()>& make_output) override {
    const cv::Size size(static_cast<int>(left.width), static_cast<int>(left.height));
    return matcher_->compute(
        size, [&](cv::Mat& into) { write_mono8(left, kLeftImage, into); },
        [&](cv::Mat& into) { write_mono8(right, kRightImage, into); }, params_, make_output);
  }

 private:
  StereoParams params_;
  std::unique_ptr<cuda::BlockMatcher> matcher_;
};

}  // namespace

std::unique_ptr<DisparityComputation> make_cuda_disparity(const StereoParams& params) {
  require_device_block_matching("cuda", params);
  return std::make_unique<CudaDisparity>(params);
}

}  // namespace robotperf::perception
