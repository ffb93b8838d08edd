// Rectify's remap and resize's resize on the OpenCL device (opencl_device()), through OpenCV's
// transparent API: the opencl backend of image_proc_computations.hpp. OpenCV hands to the CPU,
// without saying, what its OpenCL kernels do not compute; this backend refuses it instead, so that
// the CPU is never timed under its name (docs/design.md §6).
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "device_stage.hpp"
#include "image_proc_computations.hpp"
#include "robotperf/perception/opencl_device.hpp"

namespace robotperf::perception {
namespace {

// OpenCV's OpenCL remap and resize (ocl_remap, ocl_resize) compute INTER_NEAREST and
// INTER_LINEAR, and resize INTER_AREA when it does not enlarge.
void require_opencl_interpolation(int interpolation, bool is_resize) {
  require_interpolation_in_range(interpolation);
  const bool on_opencl = interpolation == cv::INTER_NEAREST || interpolation == cv::INTER_LINEAR ||
                         (is_resize && interpolation == cv::INTER_AREA);
  if (!on_opencl) {
    throw std::invalid_argument(
        "interpolation " + std::to_string(interpolation) +
        " has no opencl backend: OpenCV's OpenCL " +
        (is_resize ? "resize has INTER_NEAREST (0), INTER_LINEAR (1) and, to shrink, INTER_AREA (3)"
                   : "remap has INTER_NEAREST (0) and INTER_LINEAR (1)") +
        " and computes the others on the CPU; use one of those or the cpu backend");
  }
}

// The pixels OpenCV's OpenCL remap and resize compute: 1 to 4 channels, not doubles (fp64 is
// optional in OpenCL, and PoCL fails to build remap's kernel for them).
void require_opencl_pixels(const cv::Mat& image, const std::string& encoding, const char* what) {
  if (image.channels() > 4 || image.depth() == CV_64F) {
    throw std::invalid_argument(std::string(what) + ": encoding '" + encoding +
                                "' has no opencl backend: OpenCV's OpenCL remap and resize take "
                                "1 to 4 channels, not 64F, and compute others on the CPU; use the "
                                "cpu backend");
  }
}

// OpenCV's OpenCL resize uses INTER_AREA to shrink only (x and y scales at most 1); enlarging it
// does on the CPU.
void require_opencl_area_shrinks(double scale_x, double scale_y, const std::string& resizing) {
  if (scale_x > 1.0 || scale_y > 1.0) {
    throw std::invalid_argument("resize: interpolation 3 (INTER_AREA) enlarging " + resizing +
                                " has no opencl backend: OpenCV's OpenCL resize uses it to shrink "
                                "only and enlarges on the CPU; use INTER_LINEAR (1) or the cpu "
                                "backend");
  }
}

// The input and output images on the device, kept from one message to the next.
struct DeviceImages {
  cv::UMat in, out;

  // Computes `compute(in, out)` on the device: uploads `host_in`, and downloads the result into
  // `host_out` (already the output's size and type: written in place).
  template <class Compute>
  void compute(const cv::Mat& host_in, cv::Mat& host_out, const Compute& compute) {
    {
      DeviceStage upload("upload", host_in.total() * host_in.elemSize(), opencl_queue());
      host_in.copyTo(in);
    }
    {
      DeviceStage stage("compute", 0, opencl_queue());
      compute(in, out);
    }
    uint8_t* const data = host_out.data;
    {
      DeviceStage download("download", host_out.total() * host_out.elemSize(), opencl_queue());
      out.copyTo(host_out);
    }
    if (host_out.data != data)
      throw std::logic_error("the device's output has another size or type");
  }
};

class OpenClRectify final : public RectifyComputation {
 public:
  explicit OpenClRectify(int interpolation) : interpolation_(interpolation) {}

  void set_maps(const cv::Mat& map_xy, const cv::Mat& map_fraction) override {
    map_xy.copyTo(map_xy_);
    map_fraction.copyTo(map_fraction_);
  }

  void remap(const cv::Mat& raw, const std::string& encoding,
             const std::function<cv::Mat()>& make_output) override {
    require_opencl_pixels(raw, encoding, "rectify");
    cv::Mat rectified = make_output();
    const cv::Scalar border = remap_border(raw.depth());
    images_.compute(raw, rectified, [&](const cv::UMat& in, cv::UMat& out) {
      cv::remap(in, out, map_xy_, map_fraction_, interpolation_, cv::BORDER_CONSTANT, border);
    });
  }

 private:
  int interpolation_;
  cv::UMat map_xy_, map_fraction_;
  DeviceImages images_;
};

class OpenClResize final : public ResizeComputation {
 public:
  explicit OpenClResize(int interpolation) : interpolation_(interpolation) {}

  using ResizeComputation::resize;
  void resize(const cv::Mat& in, const std::string& encoding, const ResizeShape& shape,
              const std::function<cv::Mat()>& make_output) override {
    require_opencl_pixels(in, encoding, "resize");
    const cv::Size in_size = shape.in_size, out_size = shape.out_size;
    // OpenCV's OpenCL resize takes images over 10 px each way.
    if (in_size.width <= 10 || in_size.height <= 10) {
      throw std::invalid_argument("resize: a " + std::to_string(in_size.width) + "x" +
                                  std::to_string(in_size.height) +
                                  " image has no opencl backend: OpenCV's OpenCL resize takes "
                                  "images over 10 px each way and resizes smaller ones on the "
                                  "CPU; use the cpu backend");
    }
    if (interpolation_ == cv::INTER_AREA) {
      require_opencl_area_shrinks(
          shape.inv_scale_x, shape.inv_scale_y,
          std::to_string(in_size.width) + "x" + std::to_string(in_size.height) + " to " +
              std::to_string(out_size.width) + "x" + std::to_string(out_size.height));
    }
    cv::Mat out = make_output();
    images_.compute(in, out, [&](const cv::UMat& device_in, cv::UMat& device_out) {
      resize_as(device_in, device_out, shape, interpolation_);
    });
  }

 private:
  int interpolation_;
  DeviceImages images_;
};

}  // namespace

std::unique_ptr<RectifyComputation> make_opencl_rectify(int interpolation) {
  require_opencl_interpolation(interpolation, false);
  opencl_device();
  return std::make_unique<OpenClRectify>(interpolation);
}

std::unique_ptr<ResizeComputation> make_opencl_resize(const ResizeParams& params) {
  require_opencl_interpolation(params.interpolation, true);
  if (params.interpolation == cv::INTER_AREA && params.use_scale) {
    require_opencl_area_shrinks(
        params.scale_width, params.scale_height,
        cv::format("by scale_width %g, scale_height %g", params.scale_width, params.scale_height));
  }
  opencl_device();
  return std::make_unique<OpenClResize>(params.interpolation);
}

}  // namespace robotperf::perception
