#include "robotperf/perception/stereo_image_proc.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "robotperf/perception/cuda_device.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "stereo_image_proc_computations.hpp"

namespace robotperf::perception {
namespace {

constexpr int kDisparitiesPerPixel = 16;  // OpenCV's fixed-point disparity scale

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

bool odd_in(int v, int lo, int hi) {
  return v % 2 == 1 && v >= lo && v <= hi;
}

}  // namespace

void validate(const StereoParams& p) {
  const bool bm = p.algorithm == StereoAlgorithm::kBlockMatching;
  require(
      p.algorithm == StereoAlgorithm::kBlockMatching || p.algorithm == StereoAlgorithm::kSemiGlobal,
      "stereo_algorithm must be 0 (block matching) or 1 (semi-global block matching)");
  if (bm) {
    require(odd_in(p.prefilter_size, 5, 255), "prefilter_size must be odd, 5..255");
    require(odd_in(p.correlation_window_size, 5, 255),
            "correlation_window_size must be odd, 5..255 for block matching");
    require(p.texture_threshold >= 0, "texture_threshold must be >= 0");
  } else {
    require(odd_in(p.correlation_window_size, 1, 255),
            "correlation_window_size must be odd, 1..255");
    require(p.p1 >= 0 && p.p2 > p.p1, "P2 must be greater than P1, both >= 0");
    require(p.sgbm_mode >= 0 && p.sgbm_mode <= 3, "sgbm_mode must be 0..3");
  }
  require(p.prefilter_cap >= 1 && p.prefilter_cap <= 63, "prefilter_cap must be 1..63");
  require(p.disparity_range > 0 && p.disparity_range % 16 == 0,
          "disparity_range must be a positive multiple of 16");
  require(p.uniqueness_ratio >= 0, "uniqueness_ratio must be >= 0");
  require(p.speckle_size >= 0, "speckle_size must be >= 0");
  require(p.speckle_range >= 0, "speckle_range must be >= 0");
}

void require_device_block_matching(const char* backend, const StereoParams& params) {
  const std::string name = backend;
  require(params.algorithm == StereoAlgorithm::kBlockMatching,
          "stereo_algorithm 1 (StereoSGBM) has no " + name + " backend; use 0 (StereoBM)");
  require(params.min_disparity >= 0, "the " + name + " backend needs min_disparity >= 0");
}

std::span<const DisparityImplementation> disparity_implementations() {
  static const DisparityImplementation table[] = {{"cpu", make_cpu_disparity},
                                                  {"opencl", make_opencl_disparity, opencl_device},
                                                  {"cuda", make_cuda_disparity, cuda_device}};
  return table;
}

DisparityProcessor::DisparityProcessor(const StereoParams& params, std::string_view backend)
    : DisparityProcessor(params, implementation_on(disparity_implementations(), backend)) {}

DisparityProcessor::DisparityProcessor(const StereoParams& params,
                                       const DisparityImplementation& backend)
    : params_(params) {
  validate(params_);
  // stereo_image_proc gives disp12_max_diff to its StereoSGBM only: its StereoBM keeps OpenCV's
  // -1, no left-right check (on every backend, which all follow the cpu's StereoBM).
  if (params_.algorithm == StereoAlgorithm::kBlockMatching) params_.disp12_max_diff = -1;
  computation_ = backend.make(params_);
}

DisparityProcessor::~DisparityProcessor() = default;
DisparityProcessor::DisparityProcessor(DisparityProcessor&&) noexcept = default;
DisparityProcessor& DisparityProcessor::operator=(DisparityProcessor&&) noexcept = default;

void DisparityProcessor::compute(const msgs::Image& left, const msgs::Image& right,
                                 const msgs::CameraInfo& left_info,
                                 const msgs::CameraInfo& right_info, msgs::DisparityImage& out) {
  require(left.width == right.width && left.height == right.height,
          "disparity: left image is " + std::to_string(left.width) + "x" +
              std::to_string(left.height) + ", right image " + std::to_string(right.width) + "x" +
              std::to_string(right.height));
  require(left_info.width == left.width && left_info.height == left.height &&
              right_info.width == right.width && right_info.height == right.height,
          "disparity: image sizes do not match their CameraInfo");
  require(right_info.p[0] != 0.0, "disparity: right CameraInfo has no focal length (P[0] = 0)");
  require(left.width > 0 && left.height > 0, "disparity: empty images");
  // StereoBM's own check (cv::Exception on the cpu), made for every backend: the device kernels
  // would give an all-invalid image where the cpu gives none.
  if (params_.algorithm == StereoAlgorithm::kBlockMatching) {
    require(
        static_cast<uint32_t>(params_.correlation_window_size) < std::min(left.width, left.height),
        "disparity: correlation_window_size " + std::to_string(params_.correlation_window_size) +
            " is not smaller than the " + std::to_string(left.width) + "x" +
            std::to_string(left.height) +
            " images (StereoBM needs a window below their width and height)");
  }

  const int width = static_cast<int>(left.width);
  const int height = static_cast<int>(left.height);
  cv::Mat disparity;
  // The output message is made while a device works.
  const cv::Mat disparity16 = computation_->disparity16(left, right, [&] {
    out.header = left_info.header;
    disparity = prepare_image(out.image, left_info.header, "32FC1", width, height);
  });
  // Principal points of a rectified pair may differ in x; disparities are relative to them.
  const double cx_offset = left_info.p[2] - right_info.p[2];
  disparity16.convertTo(disparity, CV_32F, 1.0 / kDisparitiesPerPixel, -cx_offset);

  out.f = static_cast<float>(right_info.p[0]);
  out.t = static_cast<float>(-right_info.p[3] / right_info.p[0]);

  // Pixels the matcher can give a disparity to: the correlation window fits, and the search
  // range fits left of the pixel.
  const int border = params_.correlation_window_size / 2;
  const int min_d = params_.min_disparity;
  const int left_edge = params_.disparity_range + min_d + border - 1;
  const int right_margin = min_d >= 0 ? border + min_d : std::max(border, -min_d);
  const int right_edge = width - 1 - right_margin;
  const int top = border;
  const int bottom = height - 1 - border;
  out.valid_window.x_offset = static_cast<uint32_t>(std::max(left_edge, 0));
  out.valid_window.y_offset = static_cast<uint32_t>(top);
  out.valid_window.width = static_cast<uint32_t>(std::max(right_edge - left_edge, 0));
  out.valid_window.height = static_cast<uint32_t>(std::max(bottom - top, 0));
  out.valid_window.do_rectify = false;
  out.min_disparity = static_cast<float>(min_d);
  out.max_disparity = static_cast<float>(min_d + params_.disparity_range - 1);
  out.delta_d = 1.0f / kDisparitiesPerPixel;
}

}  // namespace robotperf::perception
