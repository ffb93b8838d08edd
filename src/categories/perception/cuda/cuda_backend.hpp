// Private to the perception category: the kernels' work on a CUDA device, for the cuda
// implementations of Rectifier's, Resizer's, PointCloudXyzrgbProcessor's and DisparityProcessor's
// computations (cuda_image_proc.cpp, cuda_depth_image_proc.cpp, cuda_stereo_image_proc.cpp). Free
// of CUDA's headers, so that those compile in every build; the make_*
// functions give the CUDA build's objects (cuda_image_ops.cpp, cuda_stereo_bm.cpp) or, in a build
// without the toolkit, throw (cuda_missing.cpp).
//
// Each object owns a CUDA stream and the buffers it reuses from message to message (device memory,
// pinned host staging). Every call uploads its inputs and downloads its outputs, as a node whose
// messages live in host memory must (docs/design.md §6), in the device stages "upload",
// "compute" and "download", except where a device-resident run hands an image from one node to
// the next on the device (ResidentPixels). Not thread-safe: one object per node.
#pragma once

#include <functional>
#include <memory>
#include <opencv2/core.hpp>

#include "../xyzrgb_model.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "robotperf/perception/stereo_image_proc.hpp"

namespace robotperf::perception::cuda {

// cv::remap(in, out, map_xy, map_fraction, INTER_LINEAR, BORDER_CONSTANT) with a border of 0, NaN
// for float images.
class Remapper {
 public:
  virtual ~Remapper() = default;
  // The fixed-point maps (CV_16SC2 source pixels, CV_16UC1 interpolation-table indices) to the
  // device: once per camera model, not per message.
  virtual void set_maps(const cv::Mat& map_xy, const cv::Mat& map_fraction) = 0;
  // The output is what `make_output` returns, of the maps' size and `in`'s type (written in
  // place): it is called once the device has its work, so that the host makes the output message
  // meanwhile. Images: 8-bit, 16-bit unsigned or 32-bit float with 1 to 4 channels, else
  // std::invalid_argument.
  virtual void remap(const cv::Mat& in, const std::function<cv::Mat()>& make_output) = 0;
  // As remap(), into device memory of the output's own, finished on return, with no download.
  virtual ResidentPixels remap_to_device(const cv::Mat& in) = 0;
};

// cv::resize(in, out, out_size, INTER_LINEAR) where cv::resize would take `inv_scale_x` and
// `inv_scale_y` (the scales it was given, or out's size over in's). The output is what
// `make_output` returns, of out_size and in's type, made while the device works (as Remapper's).
// Images as Remapper's.
class ImageResizer {
 public:
  virtual ~ImageResizer() = default;
  virtual void resize(const cv::Mat& in, cv::Size out_size, double inv_scale_x, double inv_scale_y,
                      const std::function<cv::Mat()>& make_output) = 0;
  // As resize(), from pixels another node left on the device (no upload).
  virtual void resize(const ResidentPixels& in, cv::Size out_size, double inv_scale_x,
                      double inv_scale_y, const std::function<cv::Mat()>& make_output) = 0;
};

// point_cloud_xyzrgb's points of `depth` (32FC1 or 16UC1, as model.metres) and its 8-bit `colour`
// (resized on the device, bilinear, where its size differs), into `cloud`: depth.rows x
// (depth.cols * 32) bytes, CV_8UC1, every byte written.
class PointCloudMaker {
 public:
  virtual ~PointCloudMaker() = default;
  virtual void xyzrgb(const cv::Mat& depth, const cv::Mat& colour, const XyzrgbModel& model,
                      cv::Mat& cloud) = 0;
};

// Writes one image of a stereo pair as mono8 into `into` (the pair's size, CV_8UC1, written in
// place).
using MonoWriter = std::function<void(cv::Mat& into)>;

// StereoBM (params.algorithm block matching, min_disparity >= 0) on a rectified pair of `size`,
// which `left` and `right` write as mono8 straight into the pinned memory of its upload (no host
// copy of the pair): the fixed-point disparity (1/16 px, filtered pixels (min_disparity - 1) * 16)
// after the speckle filter, all on the device, returned in the pinned memory of its download,
// valid until the next call. `meanwhile` runs on the host once the device has the work (the node
// makes its output message then).
class BlockMatcher {
 public:
  virtual ~BlockMatcher() = default;
  virtual cv::Mat compute(cv::Size size, const MonoWriter& left, const MonoWriter& right,
                          const StereoParams& params, const std::function<void()>& meanwhile) = 0;
};

// Each throws std::invalid_argument with cuda_device()'s one line when there is no device or no
// CUDA build, std::runtime_error when CUDA fails.
std::unique_ptr<Remapper> make_remapper();
std::unique_ptr<ImageResizer> make_resizer();
std::unique_ptr<PointCloudMaker> make_point_cloud_maker();
// Also throws std::invalid_argument, saying why, for a window and range the device's tiles
// cannot take (checked before the device is asked for).
std::unique_ptr<BlockMatcher> make_block_matcher(const StereoParams& params);

}  // namespace robotperf::perception::cuda
