#pragma once

// Image processing as ROS 2 image_proc does it (RectifyNode, ResizeNode), on OpenCV, without
// the node plumbing: these functions are what the graph nodes call per message.

#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/plugin/kernel.hpp"

namespace robotperf::perception {

// ---------------------------------------------------------------------------------------------
// sensor_msgs/Image <-> cv::Mat
// ---------------------------------------------------------------------------------------------

// The OpenCV element type (e.g. CV_8UC3) that stores one pixel of a ROS image encoding, as
// cv_bridge maps them: rgb8/bgr8, rgba8/bgra8, rgb16/bgr16, rgba16/bgra16, mono8, mono16,
// bayer_*8/16, yuv422/uyvy/yuyv, and the generic "<depth>C<channels>" names (8UC1, 16UC1,
// 32FC1, 64FC3, ...). Throws std::invalid_argument for any other encoding.
int cv_type_from_encoding(std::string_view encoding);

// Zero-copy views of an image's pixel buffer. They validate first and throw
// std::invalid_argument if the encoding is unknown, the image is big-endian with multi-byte
// elements, step is smaller than a row or not a multiple of the element size, or data does
// not hold exactly step * height bytes. A zero-sized image gives an empty cv::Mat.
// The view stays valid while image.data is neither resized nor destroyed.
cv::Mat image_view(msgs::Image& image);
// The returned header is mutable only because cv::Mat has no read-only form; never write
// through it.
cv::Mat image_view(const msgs::Image& image);

// Makes `image` a densely packed width x height image with `encoding`, `header` and the host's
// byte order (as cv_bridge does), reusing the capacity of image.data, and returns a view of its
// (uninitialised) pixels. OpenCV functions given this view as destination write into
// image.data without reallocating.
cv::Mat prepare_image(msgs::Image& image, const msgs::Header& header, std::string_view encoding,
                      int width, int height);

// cv_bridge's conversion to mono8 of the 8-bit encodings mono8 (8UC1; `mono` is then a view of
// the image), rgb8, bgr8, rgba8 and bgra8 (converted into `mono`, which a view left by an
// earlier call is never: it gets a buffer of its own). Throws std::invalid_argument
// for another encoding, naming it after `what` ("disparity: left image").
void to_mono8(const msgs::Image& image, const std::string& what, cv::Mat& mono);
// to_mono8() into memory of the caller's, written in place: `into` is image's size, CV_8UC1 (else
// std::logic_error), and gets a copy of a mono8 image.
void write_mono8(const msgs::Image& image, const std::string& what, cv::Mat& into);

// ---------------------------------------------------------------------------------------------
// Backends
// ---------------------------------------------------------------------------------------------

// Each processor here and in depth_image_proc.hpp and stereo_image_proc.hpp computes through an
// implementation of its computation on one backend, chosen by name when it is made: "cpu" (the
// host), "opencl" (opencl_device(), through OpenCV's transparent API) or "cuda" (cuda_device(),
// kernels of robotperf's own, each object on a CUDA stream of its own), each in an implementation
// unit of its own. With a device every call uploads its input and downloads its output, as a node
// whose messages live in host memory must (docs/design.md §6).
template <class Computation, class... Settings>
struct Implementation {
  const char* backend = "";
  // Throws std::invalid_argument for settings the backend does not compute (naming them), and
  // without its device; for cuda in a robotperf built without it, with kCudaNotBuilt's line.
  std::unique_ptr<Computation> (*make)(Settings...) = nullptr;
  // The device it computes on, as results record it; null for the host's cpu.
  const plugin::DeviceInfo& (*device)() = nullptr;
  // Rectify hands images to resize on this backend's device (a device-resident run).
  bool image_resident = false;
};

// The implementation on `backend` in `table`; throws std::invalid_argument naming the table's
// backends when it has none there.
template <class I>
const I& implementation_on(std::span<const I> table, std::string_view backend) {
  std::string names;
  for (const I& i : table) {
    if (i.backend == backend) return i;
    names += (names.empty() ? "" : ", ") + std::string(i.backend);
  }
  throw std::invalid_argument("no image backend '" + std::string(backend) + "' (" + names + ")");
}

class RectifyComputation;
class ResizeComputation;
struct ResizeParams;
using RectifyImplementation = Implementation<RectifyComputation, int>;
using ResizeImplementation = Implementation<ResizeComputation, const ResizeParams&>;
// The implementations of Rectifier's and Resizer's computations: cpu first, then opencl and cuda.
std::span<const RectifyImplementation> rectify_implementations();
std::span<const ResizeImplementation> resize_implementations();

// An image's pixels left on the CUDA device for the next node of the process, in a
// device-resident run (docs/design.md §6: type adaptation, as REP 2007 and NITROS do): dense
// rows x cols of OpenCV `type`, finished before the message that carries them is published, and
// held until the last message that refers to them goes.
struct ResidentPixels {
  std::shared_ptr<void> memory;
  int rows = 0, cols = 0, type = 0;
};

// A message for such pixels: `image` has its header, size, encoding and step and no data (what a
// subscriber outside the device would have to download is not there). resident_pixels() finds
// the pixels again from the message, or gives nullptr for any other message.
std::shared_ptr<const msgs::Image> resident_image_message(msgs::Image&& image,
                                                          ResidentPixels pixels);
const ResidentPixels* resident_pixels(const std::shared_ptr<const msgs::Image>& message);

// ---------------------------------------------------------------------------------------------
// Rectification (image_proc RectifyNode + image_geometry::PinholeCameraModel)
// ---------------------------------------------------------------------------------------------

// Rectifies camera images with the undistort-rectify map of their CameraInfo. The map is built
// (cv::initUndistortRectifyMap, fixed-point CV_16SC2 maps) only when the camera model changes:
// size, distortion model, D, K, R, P or binning rebuild it; a new ROI only re-crops it.
//
// Per image, in image_proc's order: K[0] == 0 (uncalibrated) throws std::invalid_argument;
// if every element of D is zero (or D is empty) the image passes through unchanged (copied),
// whatever R and P say; otherwise the image is remapped with border constant 0 (NaN for float
// images). Distortion models: plumb_bob (D of 4 or 5), rational_polynomial (D of 8); others
// throw.
// Binning and ROI are honoured as image_geometry does; the image must have the reduced size
// (ROI size divided by binning), else std::invalid_argument.
//
// Not thread-safe: one Rectifier per stream.
class Rectifier {
 public:
  // `interpolation`: cv::InterpolationFlags value, INTER_NEAREST .. INTER_LANCZOS4
  // (image_proc's "interpolation" parameter, default 1 = INTER_LINEAR); `backend`: an entry of
  // rectify_implementations(), by name or itself.
  // With a device backend the maps are uploaded once per camera model. The cuda backend has
  // INTER_LINEAR only (std::invalid_argument naming the interpolation otherwise), OpenCV's CPU
  // arithmetic (8-bit images within 1 of the cpu's, as a rule the same) for 8-bit, 16-bit
  // unsigned and float images of 1 to 4 channels; it throws std::invalid_argument without its
  // device (cuda_device()). The opencl backend has what OpenCV's OpenCL remap computes:
  // INTER_NEAREST and INTER_LINEAR (std::invalid_argument naming another), and per image 1 to 4
  // channels, not 64F (rectify() throws std::invalid_argument for others); it throws
  // std::invalid_argument without its device (opencl_device()), which it chooses if none was.
  explicit Rectifier(int interpolation = cv::INTER_LINEAR, std::string_view backend = "cpu");
  Rectifier(int interpolation, const RectifyImplementation& backend);
  ~Rectifier();
  Rectifier(Rectifier&&) noexcept;
  Rectifier& operator=(Rectifier&&) noexcept;

  // Writes the rectified image (same header, encoding and size) into `rectified`, reusing its
  // buffer. `rectified` must not be `raw`.
  void rectify(const msgs::Image& raw, const msgs::CameraInfo& info, msgs::Image& rectified);
  msgs::Image rectify(const msgs::Image& raw, const msgs::CameraInfo& info);
  // As rectify(), with the rectified pixels left on the device (cuda only, else
  // std::logic_error): `rectified` gets the header, size and encoding but no data. Where
  // rectifying is a copy (D all zero) there is nothing to compute on the device: `rectified` then
  // holds the pixels, on the host, and the result is empty.
  std::optional<ResidentPixels> rectify_on_device(const msgs::Image& raw,
                                                  const msgs::CameraInfo& info,
                                                  msgs::Image& rectified);

  int interpolation() const { return interpolation_; }
  // How many times the full undistort-rectify map has been computed.
  uint64_t map_computations() const { return map_computations_; }

 private:
  // Checks `raw` and `info` and readies the maps; false where rectifying is a copy (D all zero),
  // which it has made into `rectified`.
  bool prepare(const msgs::Image& raw, const msgs::CameraInfo& info, msgs::Image& rectified);

  // What the full-resolution map depends on, normalised as image_geometry does (binning 0 = 1).
  struct MapInputs {
    uint32_t width = 0;
    uint32_t height = 0;
    std::string distortion_model;
    std::vector<double> d;
    std::array<double, 9> k{};
    std::array<double, 9> r{};
    std::array<double, 12> p{};
    uint32_t binning_x = 1;
    uint32_t binning_y = 1;
    // Whether `info` has these inputs (compared in place: no copy per image).
    bool matches(const msgs::CameraInfo& info) const;
  };

  void update_maps(const msgs::CameraInfo& info);

  int interpolation_;
  uint64_t map_computations_ = 0;
  bool have_maps_ = false;
  MapInputs map_inputs_;
  // ROI in full-resolution pixels, all-zero normalised to the full image.
  cv::Rect roi_;
  cv::Mat full_map_xy_, full_map_fraction_;
  // The maps cropped to the ROI (the full maps themselves when the ROI is the full image).
  cv::Mat map_xy_, map_fraction_;
  // The remap on the backend, with what it keeps there (maps, buffers, a stream).
  std::unique_ptr<RectifyComputation> computation_;
};

// ---------------------------------------------------------------------------------------------
// Resize (image_proc ResizeNode)
// ---------------------------------------------------------------------------------------------

// image_proc ResizeNode's parameters, with its defaults.
struct ResizeParams {
  // true: scale by scale_width x scale_height; false: resize to width x height.
  bool use_scale = true;
  double scale_height = 1.0;
  double scale_width = 1.0;
  // Target size when !use_scale; -1 keeps the input's.
  int height = -1;
  int width = -1;
  // cv::InterpolationFlags value, INTER_NEAREST .. INTER_LANCZOS4.
  int interpolation = cv::INTER_LINEAR;
};

// Resizes images as image_proc's ResizeNode, keeping what a node keeps from message to message on
// its backend (with cuda: its stream and buffers). Not thread-safe: one per node.
class Resizer {
 public:
  // `backend`: an entry of resize_implementations(), by name or itself. Throws
  // std::invalid_argument for an interpolation out of range, with cuda for any but
  // INTER_LINEAR (naming it), without its backend's device (cuda_device(), opencl_device()), and
  // with opencl for what OpenCV's OpenCL resize does not compute (naming it): any but
  // INTER_NEAREST, INTER_LINEAR and INTER_AREA, and INTER_AREA by a scale over 1.
  explicit Resizer(const ResizeParams& params, std::string_view backend = "cpu");
  Resizer(const ResizeParams& params, const ResizeImplementation& backend);
  ~Resizer();
  Resizer(Resizer&&) noexcept;
  Resizer& operator=(Resizer&&) noexcept;

  // Resizes `image` into `out` (same header and encoding, reusing out's buffer; must not be
  // `image`) and writes `info` adjusted to the new size into `out_info` (may be `info`): height
  // and width, K[0], K[2], P[0], P[2], P[3] times the x scale, K[4], K[5], P[5], P[6] times the y
  // scale, ROI offsets and size scaled (truncated), as image_proc does. With use_scale, the image
  // size is rounded (cv::resize) and the CameraInfo size truncated, as in image_proc.
  // Throws std::invalid_argument for non-positive scales or sizes, or a bad image, and with
  // opencl for an image OpenCV's OpenCL resize would resize on the CPU: more than 4 channels,
  // 64F, 10 px or less either way, or enlarged with INTER_AREA. cuda follows
  // OpenCV's CPU arithmetic for INTER_LINEAR (8-bit images within 1 of the cpu's, as a rule the
  // same) for 8-bit, 16-bit unsigned and float images of 1 to 4 channels.
  // With `pixels` (cuda only, else std::logic_error), `image`'s pixels are those on the device
  // (ResidentPixels of its size and type) and image.data is not read.
  void resize(const msgs::Image& image, const msgs::CameraInfo& info, msgs::Image& out,
              msgs::CameraInfo& out_info, const ResidentPixels* pixels = nullptr);

 private:
  ResizeParams params_;
  // The resize on the backend, with what it keeps there from one message to the next.
  std::unique_ptr<ResizeComputation> computation_;
};

// Resizer(params, backend).resize(image, info, out, out_info): a device backend's buffers (and
// with cuda, its stream) for this call only.
void resize(const msgs::Image& image, const msgs::CameraInfo& info, const ResizeParams& params,
            msgs::Image& out, msgs::CameraInfo& out_info, std::string_view backend = "cpu");

}  // namespace robotperf::perception
