// Private to the perception category: what Rectifier and Resizer leave to their backend, and the
// implementations of it, one per backend in a unit of its own: image_proc_cpu.cpp,
// image_proc_opencl.cpp and cuda/cuda_image_proc.cpp. image_proc.cpp lists them by backend name.
#pragma once

#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "robotperf/perception/image_proc.hpp"

namespace robotperf::perception {

// The remap of Rectifier, with the undistort-rectify maps of the current camera model. Border 0,
// NaN for float images, as image_geometry does.
class RectifyComputation {
 public:
  virtual ~RectifyComputation() = default;
  // The fixed-point maps (CV_16SC2 source pixels, CV_16UC1 interpolation-table indices): once per
  // camera model, not per message (a device keeps them).
  virtual void set_maps(const cv::Mat& map_xy, const cv::Mat& map_fraction) = 0;
  // Remaps `raw` (its pixels of `encoding`, named in refusals) into what `make_output` returns (the
  // maps' size and raw's type, written in place). A device backend calls it once the device has
  // its work, so that the host makes the output message meanwhile.
  virtual void remap(const cv::Mat& raw, const std::string& encoding,
                     const std::function<cv::Mat()>& make_output) = 0;
  // As remap(), into device memory of the output's own, finished on return, with no download.
  // Only a backend whose images can stay on the device has it: std::logic_error on the others.
  virtual ResidentPixels remap_to_device(const cv::Mat& raw);
};

// One image's resize, as Resizer works it out from its parameters and the image.
struct ResizeShape {
  cv::Size in_size, out_size;
  // The scales cv::resize computes with: those ResizeParams gave (given_scales), or out_size over
  // in_size.
  double inv_scale_x = 0.0, inv_scale_y = 0.0;
  bool given_scales = false;
};

// The resize of Resizer, with the interpolation its backend was made for.
class ResizeComputation {
 public:
  virtual ~ResizeComputation() = default;
  // Resizes `in` (its pixels of `encoding`, named in refusals) into what `make_output` returns
  // (out_size, in's type, written in place), made while a device works, as RectifyComputation's.
  virtual void resize(const cv::Mat& in, const std::string& encoding, const ResizeShape& shape,
                      const std::function<cv::Mat()>& make_output) = 0;
  // As resize(), from pixels another node left on the device (no upload). Only a backend whose
  // images can stay on the device has it: std::logic_error on the others.
  virtual void resize(const ResidentPixels& in, const ResizeShape& shape,
                      const std::function<cv::Mat()>& make_output);
};

// Shared by the backends' implementations.
// Throws std::invalid_argument for an interpolation outside INTER_NEAREST .. INTER_LANCZOS4.
void require_interpolation_in_range(int interpolation);
// cv::resize of `in` into `out` as `shape` says, on the host's images or OpenCL's.
void resize_as(cv::InputArray in, cv::OutputArray out, const ResizeShape& shape, int interpolation);
// The value remap gives pixels outside the raw image: NaN for float images, else 0.
cv::Scalar remap_border(int depth);

// The implementations; each throws std::invalid_argument for an interpolation (or, for resize,
// a parameter) its backend does not compute, naming it, and without its backend's device.
std::unique_ptr<RectifyComputation> make_cpu_rectify(int interpolation);
std::unique_ptr<RectifyComputation> make_opencl_rectify(int interpolation);
std::unique_ptr<RectifyComputation> make_cuda_rectify(int interpolation);
std::unique_ptr<ResizeComputation> make_cpu_resize(const ResizeParams& params);
std::unique_ptr<ResizeComputation> make_opencl_resize(const ResizeParams& params);
std::unique_ptr<ResizeComputation> make_cuda_resize(const ResizeParams& params);

}  // namespace robotperf::perception
