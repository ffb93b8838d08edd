// Private to the perception category: what DisparityProcessor leaves to its backend, and the
// implementations of it, one per backend in a unit of its own: stereo_image_proc_cpu.cpp,
// stereo_image_proc_opencl.cpp and cuda/cuda_stereo_image_proc.cpp. stereo_image_proc.cpp lists
// them by backend name.
#pragma once

#include <functional>
#include <memory>
#include <opencv2/core.hpp>

#include "robotperf/perception/stereo_image_proc.hpp"

namespace robotperf::perception {

// The matcher of DisparityProcessor, made for the (checked) parameters it was given.
class DisparityComputation {
 public:
  virtual ~DisparityComputation() = default;
  // The fixed-point disparity (1/16 px, invalid pixels (min_disparity - 1) * 16) of a rectified
  // pair, each image converted to mono8 (refusals name it kLeftImage, kRightImage). `make_output`
  // runs once, on a device backend while the device works. Valid until the next call.
  virtual cv::Mat disparity16(const msgs::Image& left, const msgs::Image& right,
                              const std::function<void()>& make_output) = 0;

  static inline const std::string kLeftImage = "disparity: left image";
  static inline const std::string kRightImage = "disparity: right image";
};

// The device backends run StereoBM with min_disparity >= 0 only: std::invalid_argument naming
// `backend` otherwise.
void require_device_block_matching(const char* backend, const StereoParams& params);

std::unique_ptr<DisparityComputation> make_cpu_disparity(const StereoParams& params);
std::unique_ptr<DisparityComputation> make_opencl_disparity(const StereoParams& params);
std::unique_ptr<DisparityComputation> make_cuda_disparity(const StereoParams& params);

}  // namespace robotperf::perception
