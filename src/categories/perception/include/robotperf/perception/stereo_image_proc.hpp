#pragma once

// Stereo disparity as ROS 2 stereo_image_proc's DisparityNode computes it, on OpenCV's StereoBM or
// StereoSGBM, without the node plumbing.

#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"
#include "robotperf/perception/image_proc.hpp"

namespace robotperf::perception {

enum class StereoAlgorithm {
  kBlockMatching = 0,  // cv::StereoBM
  kSemiGlobal = 1,     // cv::StereoSGBM
};

// stereo_image_proc's parameters, with its defaults (docs/design.md §5).
struct StereoParams {
  StereoAlgorithm algorithm = StereoAlgorithm::kBlockMatching;
  int prefilter_size = 9;            // BM only: odd, 5..255
  int prefilter_cap = 31;            // 1..63
  int correlation_window_size = 15;  // odd; BM 5..255, SGBM 1..255
  int min_disparity = 0;
  int disparity_range = 64;    // positive multiple of 16
  int texture_threshold = 10;  // BM only
  int speckle_size = 100;
  int speckle_range = 4;
  int uniqueness_ratio = 15;
  // SGBM only (StereoBM, as stereo_image_proc's, makes no left-right check).
  int p1 = 200;
  int p2 = 400;
  int disp12_max_diff = 0;
  int sgbm_mode = 0;  // cv::StereoSGBM mode: 0 SGBM, 1 HH, 2 SGBM_3WAY, 3 HH4
};

// Throws std::invalid_argument naming the first parameter out of its range.
void validate(const StereoParams& params);

// Computes the disparity of a rectified stereo pair. Per pair, as stereo_image_proc:
// - both images are converted to mono8 (from mono8, rgb8, bgr8, rgba8 or bgra8; others throw);
// - the matcher gives fixed-point disparities (1/16 px); the output image is 32FC1 with
//   d = fixed / 16 - (cx_left - cx_right), so that invalid pixels read min_disparity - 1 (less
//   any principal-point offset);
// - header and image.header = the left CameraInfo's header; f = right P[0] (fx); t = baseline =
//   -right P[3] / right P[0]; valid_window = the region where the matcher can produce a
//   disparity (left border of disparity_range + min_disparity + window/2 - 1, window/2 on the
//   other sides); min_disparity, max_disparity = min + range - 1, delta_d = 1/16.
// Throws std::invalid_argument when the images differ in size, do not match their CameraInfo,
// are (StereoBM, on every backend) no wider or taller than correlation_window_size, or the right
// CameraInfo has no focal length.
//
// The backend is an entry of disparity_implementations(), by name or itself. With opencl or cuda,
// StereoBM runs on the device (kernels of robotperf's own:
// OpenCV's OpenCL StereoBM has no texture check; the cuda kernels are their port, on a CUDA
// stream of the processor's own); each pair is uploaded and its disparity downloaded; the
// speckle filter runs on the host for opencl, on the device for cuda (StereoBM makes no
// left-right check). The cuda backend converts the pair to mono8 straight into the pinned memory
// it uploads from, and the float disparity straight from the memory it downloads into. Its answer
// agrees with the cpu's within 1 px on >= 95 % of the pixels the cpu gives a disparity. StereoSGBM,
// and a negative min_disparity, have no device backend (the constructor throws
// std::invalid_argument), nor has a device backend without its device (cuda_device(),
// opencl_device()).
//
// Not thread-safe: one processor per stream.
class DisparityComputation;
using DisparityImplementation = Implementation<DisparityComputation, const StereoParams&>;
// cpu first, then opencl and cuda.
std::span<const DisparityImplementation> disparity_implementations();

class DisparityProcessor {
 public:
  explicit DisparityProcessor(const StereoParams& params = {}, std::string_view backend = "cpu");
  DisparityProcessor(const StereoParams& params, const DisparityImplementation& backend);
  ~DisparityProcessor();
  DisparityProcessor(DisparityProcessor&&) noexcept;
  DisparityProcessor& operator=(DisparityProcessor&&) noexcept;
  void compute(const msgs::Image& left, const msgs::Image& right, const msgs::CameraInfo& left_info,
               const msgs::CameraInfo& right_info, msgs::DisparityImage& out);
  const StereoParams& params() const { return params_; }

 private:
  StereoParams params_;
  // The matcher on the backend, with what it keeps there from one pair to the next.
  std::unique_ptr<DisparityComputation> computation_;
};

}  // namespace robotperf::perception
