// Rectify's remap and resize's resize on the CUDA device: the cuda backend of
// image_proc_computations.hpp, on the device work of cuda_backend.hpp (which, in a build without
// the toolkit, says so in one line when it is made). Compiled by the host compiler in every build.
#include <stdexcept>
#include <string>

#include "../image_proc_computations.hpp"
#include "cuda_backend.hpp"

namespace robotperf::perception {
namespace {

// The cuda kernels interpolate linearly only.
void require_cuda_interpolation(int interpolation) {
  require_interpolation_in_range(interpolation);
  if (interpolation != cv::INTER_LINEAR) {
    throw std::invalid_argument("interpolation " + std::to_string(interpolation) +
                                " has no cuda backend: it has INTER_LINEAR (1) only");
  }
}

class CudaRectify final : public RectifyComputation {
 public:
  void set_maps(const cv::Mat& map_xy, const cv::Mat& map_fraction) override {
    remapper_->set_maps(map_xy, map_fraction);
  }
  void remap(const cv::Mat& raw, const std::string& /*encoding*/,
             const std::function<cv::Mat()>& make_output) override {
    remapper_->remap(raw, make_output);
  }
  ResidentPixels remap_to_device(const cv::Mat& raw) override {
    return remapper_->remap_to_device(raw);
  }

 private:
  std::unique_ptr<cuda::Remapper> remapper_ = cuda::make_remapper();
};

class CudaResize final : public ResizeComputation {
 public:
  void resize(const cv::Mat& in, const std::string& /*encoding*/, const ResizeShape& shape,
              const std::function<cv::Mat()>& make_output) override {
    resizer_->resize(in, shape.out_size, shape.inv_scale_x, shape.inv_scale_y, make_output);
  }
  void resize(const ResidentPixels& in, const ResizeShape& shape,
              const std::function<cv::Mat()>& make_output) override {
    resizer_->resize(in, shape.out_size, shape.inv_scale_x, shape.inv_scale_y, make_output);
  }

 private:
  std::unique_ptr<cuda::ImageResizer> resizer_ = cuda::make_resizer();
};

}  // namespace

std::unique_ptr<RectifyComputation> make_cuda_rectify(int interpolation) {
  require_cuda_interpolation(interpolation);
  return std::make_unique<CudaRectify>();
}

std::unique_ptr<ResizeComputation> make_cuda_resize(const ResizeParams& params) {
  require_cuda_interpolation(params.interpolation);
  return std::make_unique<CudaResize>();
}

}  // namespace robotperf::perception
