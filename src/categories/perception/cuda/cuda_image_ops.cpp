// The cuda backend's image work on a node's own stream: rectify's remap, resize, and the point
// cloud (whose colour image is resized on the device when its size differs).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "cuda_backend.hpp"
#include "cuda_support.hpp"
#include "robotperf/perception/cuda_device.hpp"

namespace robotperf::perception::cuda {
namespace {

constexpr int kResizeCoefScale = 1 << 11;  // INTER_RESIZE_COEF_SCALE

// saturate_cast<short>(weight * INTER_RESIZE_COEF_SCALE): rounded to nearest, ties to even, as
// cvRound rounds.
int16_t fixed_weight(float weight) {
  const long rounded = std::lrint(weight * kResizeCoefScale);
  return static_cast<int16_t>(std::clamp<long>(rounded, INT16_MIN, INT16_MAX));
}

// cv::resize's INTER_LINEAR taps along one axis, as OpenCV's resize.cpp computes them: dst pixel
// i's centre maps to (i + 0.5) * scale - 0.5 (in double, rounded to float), split into a pixel and
// a fraction. Columns clamp at the edges (fraction 0 left of the image; from the right edge on,
// the last pixel alone); rows keep both weights and clamp the rows they read.
std::vector<ResizeTap> resize_taps(int src_size, int dst_size, double scale, bool columns) {
  std::vector<ResizeTap> taps(static_cast<std::size_t>(dst_size));
  for (int i = 0; i < dst_size; ++i) {
    float fraction = static_cast<float>((i + 0.5) * scale - 0.5);
    int first = static_cast<int>(std::floor(fraction));
    fraction -= static_cast<float>(first);
    ResizeTap& t = taps[static_cast<std::size_t>(i)];
    if (columns) {
      if (first < 0) {
        first = 0;
        fraction = 0.f;
      }
      const bool alone = first + 1 >= src_size;
      if (alone) {
        first = src_size - 1;
        fraction = 0.f;
      }
      t.first = first;
      t.second = alone ? first : first + 1;
    } else {
      t.first = std::clamp(first, 0, src_size - 1);
      t.second = std::clamp(first + 1, 0, src_size - 1);
    }
    t.weight[0] = 1.f - fraction;
    t.weight[1] = fraction;
    t.fixed[0] = fixed_weight(t.weight[0]);
    t.fixed[1] = fixed_weight(t.weight[1]);
  }
  return taps;
}

// The taps of one resize geometry on the device, computed and uploaded only when it changes (a
// camera's images keep their size).
class ResizeTaps {
 public:
  void prepare(cv::Size from, cv::Size to, double inv_scale_x, double inv_scale_y, Stream& stream) {
    if (from == from_ && to == to_ && inv_scale_x == inv_scale_x_ && inv_scale_y == inv_scale_y_)
      return;
    columns_on_device_ =
        upload(resize_taps(from.width, to.width, 1.0 / inv_scale_x, true), columns_, stream);
    rows_on_device_ =
        upload(resize_taps(from.height, to.height, 1.0 / inv_scale_y, false), rows_, stream);
    stream.synchronize();
    from_ = from;
    to_ = to;
    inv_scale_x_ = inv_scale_x;
    inv_scale_y_ = inv_scale_y;
  }
  const ResizeTap* columns() const { return columns_on_device_; }
  const ResizeTap* rows() const { return rows_on_device_; }

 private:
  static const ResizeTap* upload(const std::vector<ResizeTap>& taps, Buffer& buffer,
                                 Stream& stream) {
    ResizeTap* on_device = buffer.reserve_for<ResizeTap>(taps.size());
    check(cudaMemcpyAsync(on_device, taps.data(), taps.size() * sizeof(ResizeTap),
                          cudaMemcpyHostToDevice, stream.get()),
          "cudaMemcpyAsync (resize taps)");
    return on_device;
  }

  cv::Size from_, to_;
  double inv_scale_x_ = 0, inv_scale_y_ = 0;
  Buffer columns_{Memory::kDevice}, rows_{Memory::kDevice};
  const ResizeTap* columns_on_device_ = nullptr;
  const ResizeTap* rows_on_device_ = nullptr;
};

class CudaRemapper final : public Remapper {
 public:
  void set_maps(const cv::Mat& map_xy, const cv::Mat& map_fraction) override {
    if (map_xy.type() != CV_16SC2 || map_fraction.type() != CV_16UC1 ||
        map_xy.size() != map_fraction.size()) {
      throw std::logic_error("cuda: remap takes CV_16SC2 and CV_16UC1 maps of one size");
    }
    map_xy_on_device_ = map_xy_.upload(map_xy, stream_.get());
    map_fraction_on_device_ = map_fraction_.upload(map_fraction, stream_.get());
    stream_.synchronize();
  }

  void remap(const cv::Mat& in, const std::function<cv::Mat()>& make_output) override {
    remap_into(in, out_.reserve(map_xy_on_device_.height, map_xy_on_device_.width, in.type()));
    download_overlapped(stream_, out_, make_output);
  }

  ResidentPixels remap_to_device(const cv::Mat& in) override {
    ResidentPixels out;
    out.rows = map_xy_on_device_.height;
    out.cols = map_xy_on_device_.width;
    out.type = in.type();
    out.memory = pool_->take(static_cast<std::size_t>(out.rows) * out.cols * in.elemSize());
    remap_into(in, {out.memory.get(), out.cols, out.rows});
    // Finished before the message carrying it is published: the next node's stream reads it.
    stream_.synchronize();
    return out;
  }

 private:
  // Queues the upload of `in` and its remap into `dst` (the maps' size, in's type).
  void remap_into(const cv::Mat& in, DeviceImage dst) {
    const PixelDepth depth = pixel_depth(in.type(), "rectify");
    DeviceImage src;
    {
      DeviceStage upload("upload", in.total() * in.elemSize(), stream_);
      src = in_.upload(in, stream_.get());
    }
    DeviceStage compute("compute", 0, stream_);
    remap_linear(src, dst, depth, in.channels(),
                 static_cast<const int16_t*>(map_xy_on_device_.data),
                 static_cast<const uint16_t*>(map_fraction_on_device_.data), stream_.get());
  }

  Stream stream_;
  StagedImage map_xy_, map_fraction_, in_, out_;
  DeviceImage map_xy_on_device_, map_fraction_on_device_;
  std::shared_ptr<ResidentPool> pool_ = std::make_shared<ResidentPool>();
};

class CudaResizer final : public ImageResizer {
 public:
  void resize(const cv::Mat& in, cv::Size out_size, double inv_scale_x, double inv_scale_y,
              const std::function<cv::Mat()>& make_output) override {
    DeviceImage src;
    {
      DeviceStage upload("upload", in.total() * in.elemSize(), stream_);
      src = in_.upload(in, stream_.get());
    }
    resize_from(src, in.size(), in.type(), out_size, inv_scale_x, inv_scale_y, make_output);
  }

  void resize(const ResidentPixels& in, cv::Size out_size, double inv_scale_x, double inv_scale_y,
              const std::function<cv::Mat()>& make_output) override {
    resize_from({in.memory.get(), in.cols, in.rows}, cv::Size(in.cols, in.rows), in.type, out_size,
                inv_scale_x, inv_scale_y, make_output);
  }

 private:
  // Resizes `src` (on the device: in_size, of `type`) to out_size, and downloads it into the
  // output make_output makes meanwhile.
  void resize_from(DeviceImage src, cv::Size in_size, int type, cv::Size out_size,
                   double inv_scale_x, double inv_scale_y,
                   const std::function<cv::Mat()>& make_output) {
    const PixelDepth depth = pixel_depth(type, "resize");
    // cv::resize copies an image to its own size.
    const bool copy = out_size == in_size;
    if (!copy) taps_.prepare(in_size, out_size, inv_scale_x, inv_scale_y, stream_);
    const DeviceImage dst = out_.reserve(out_size.height, out_size.width, type);
    {
      DeviceStage compute("compute", 0, stream_);
      if (copy) {
        check(cudaMemcpyAsync(dst.data, src.data, out_.bytes(), cudaMemcpyDeviceToDevice,
                              stream_.get()),
              "cudaMemcpyAsync (resize to the same size)");
      } else {
        resize_linear(src, dst, depth, CV_MAT_CN(type), taps_.columns(), taps_.rows(),
                      stream_.get());
      }
    }
    download_overlapped(stream_, out_, make_output);
  }

  Stream stream_;
  ResizeTaps taps_;
  StagedImage in_, out_;
};

class CudaPointCloudMaker final : public PointCloudMaker {
 public:
  void xyzrgb(const cv::Mat& depth, const cv::Mat& colour, const XyzrgbModel& model,
              cv::Mat& cloud) override {
    if (colour.depth() != CV_8U || static_cast<int>(colour.elemSize()) != model.colour_bytes ||
        depth.type() != (model.metres ? CV_32FC1 : CV_16UC1)) {
      throw std::logic_error("cuda: xyzrgb's images do not have the model's types");
    }
    const bool resized = colour.size() != depth.size();
    DeviceImage resized_colour;
    if (resized) {
      // As cv::resize(colour, resized, depth's size): the scales it derives from the sizes.
      taps_.prepare(colour.size(), depth.size(), static_cast<double>(depth.cols) / colour.cols,
                    static_cast<double>(depth.rows) / colour.rows, stream_);
      resized_colour = {resized_colour_.reserve(depth.total() * colour.elemSize()), depth.cols,
                        depth.rows};
    }
    const DeviceImage points = cloud_.reserve(cloud.rows, cloud.cols, CV_8UC1);
    DeviceImage depth_in, colour_in;
    {
      DeviceStage upload(
          "upload", depth.total() * depth.elemSize() + colour.total() * colour.elemSize(), stream_);
      depth_in = depth_.upload(depth, stream_.get());
      colour_in = colour_.upload(colour, stream_.get());
    }
    {
      DeviceStage compute("compute", 0, stream_);
      if (resized) {
        resize_linear(colour_in, resized_colour, PixelDepth::k8U, colour.channels(),
                      taps_.columns(), taps_.rows(), stream_.get());
        colour_in = resized_colour;
      }
      cuda::xyzrgb(depth_in, static_cast<const uint8_t*>(colour_in.data), model,
                   static_cast<uint8_t*>(points.data), stream_.get());
    }
    download(stream_, {{cloud_, cloud}});
  }

 private:
  Stream stream_;
  ResizeTaps taps_;
  StagedImage depth_, colour_, cloud_;
  Buffer resized_colour_{Memory::kDevice};
};

}  // namespace

// Each asks for the device first: no device is one line, before any CUDA call of ours.
std::unique_ptr<Remapper> make_remapper() {
  cuda_device();
  return std::make_unique<CudaRemapper>();
}

std::unique_ptr<ImageResizer> make_resizer() {
  cuda_device();
  return std::make_unique<CudaResizer>();
}

std::unique_ptr<PointCloudMaker> make_point_cloud_maker() {
  cuda_device();
  return std::make_unique<CudaPointCloudMaker>();
}

}  // namespace robotperf::perception::cuda
