// The disparity on the OpenCL device (opencl_device()), with robotperf's StereoBM there
// (stereo_bm_opencl.hpp): the opencl backend of stereo_image_proc_computations.hpp.
#include "robotperf/perception/opencl_device.hpp"
#include "stereo_bm_opencl.hpp"
#include "stereo_image_proc_computations.hpp"

namespace robotperf::perception {
namespace {

class OpenClDisparity final : public DisparityComputation {
 public:
  explicit OpenClDisparity(const StereoParams& params) : params_(params) {}

  cv::Mat disparity16(const msgs::Image& left, const msgs::Image& right,
                      const std::function<void()>& make_output) override {
    to_mono8(left, kLeftImage, left_mono_);
    to_mono8(right, kRightImage, right_mono_);
    matcher_.compute(left_mono_, right_mono_, params_, disparity16_);
    make_output();
    return disparity16_;
  }

 private:
  StereoParams params_;
  OpenClBlockMatcher matcher_;
  cv::Mat left_mono_, right_mono_, disparity16_;
};

}  // namespace

std::unique_ptr<DisparityComputation> make_opencl_disparity(const StereoParams& params) {
  require_device_block_matching("opencl", params);
  opencl_device();
  return std::make_unique<OpenClDisparity>(params);
}

}  // namespace robotperf::perception
