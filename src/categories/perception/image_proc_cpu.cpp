// Rectify's remap and resize's resize on the host CPU, with OpenCV: the cpu backend of
// image_proc_computations.hpp, and the reference every other backend's answers are compared with.
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "image_proc_computations.hpp"

namespace robotperf::perception {
namespace {

class CpuRectify final : public RectifyComputation {
 public:
  explicit CpuRectify(int interpolation) : interpolation_(interpolation) {}

  void set_maps(const cv::Mat& map_xy, const cv::Mat& map_fraction) override {
    map_xy_ = map_xy;
    map_fraction_ = map_fraction;
  }

  void remap(const cv::Mat& raw, const std::string& /*encoding*/,
             const std::function<cv::Mat()>& make_output) override {
    cv::Mat rectified = make_output();
    cv::remap(raw, rectified, map_xy_, map_fraction_, interpolation_, cv::BORDER_CONSTANT,
              remap_border(raw.depth()));
  }

 private:
  int interpolation_;
  cv::Mat map_xy_, map_fraction_;
};

class CpuResize final : public ResizeComputation {
 public:
  explicit CpuResize(int interpolation) : interpolation_(interpolation) {}

  using ResizeComputation::resize;
  void resize(const cv::Mat& in, const std::string& /*encoding*/, const ResizeShape& shape,
              const std::function<cv::Mat()>& make_output) override {
    cv::Mat out = make_output();
    const uchar* const memory = out.data;
    resize_as(in, out, shape, interpolation_);
    if (out.data != memory) {
      throw std::logic_error("resize: cv::resize chose another output size than " +
                             std::to_string(shape.out_size.width) + "x" +
                             std::to_string(shape.out_size.height));
    }
  }

 private:
  int interpolation_;
};

}  // namespace

std::unique_ptr<RectifyComputation> make_cpu_rectify(int interpolation) {
  require_interpolation_in_range(interpolation);
  return std::make_unique<CpuRectify>(interpolation);
}

std::unique_ptr<ResizeComputation> make_cpu_resize(const ResizeParams& params) {
  require_interpolation_in_range(params.interpolation);
  return std::make_unique<CpuResize>(params.interpolation);
}

}  // namespace robotperf::perception
