#include "robotperf/perception/image_proc.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <stdexcept>
#include <string>

#include "image_proc_computations.hpp"
#include "robotperf/perception/camera_model.hpp"
#include "robotperf/perception/cuda_device.hpp"
#include "robotperf/perception/opencl_device.hpp"

namespace robotperf::perception {
namespace {

constexpr uint8_t kHostIsBigEndian = std::endian::native == std::endian::big ? 1 : 0;

// Depth of a generic "<bits><U|S|F>" prefix (e.g. "16U"), or -1.
int cv_depth_from_name(std::string_view name) {
  if (name == "8U") return CV_8U;
  if (name == "8S") return CV_8S;
  if (name == "16U") return CV_16U;
  if (name == "16S") return CV_16S;
  if (name == "32S") return CV_32S;
  if (name == "32F") return CV_32F;
  if (name == "64F") return CV_64F;
  return -1;
}

// "<depth>C<channels>" as in sensor_msgs/image_encodings (8UC3, 32FC1, ...), or -1.
int cv_type_from_generic_name(std::string_view encoding) {
  const size_t c = encoding.find('C');
  if (c == std::string_view::npos) return -1;
  const int depth = cv_depth_from_name(encoding.substr(0, c));
  const std::string_view digits = encoding.substr(c + 1);
  int channels = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), channels);
  if (depth < 0 || digits.empty() || error != std::errc() || end != digits.data() + digits.size() ||
      channels < 1 || channels > CV_CN_MAX) {
    return -1;
  }
  return CV_MAKETYPE(depth, channels);
}

bool starts_with_any(std::string_view s, std::initializer_list<std::string_view> prefixes) {
  return std::any_of(prefixes.begin(), prefixes.end(),
                     [s](std::string_view p) { return s.starts_with(p); });
}

template <class ImageT>
cv::Mat make_view(ImageT& image) {
  const int type = cv_type_from_encoding(image.encoding);
  const size_t element_size = CV_ELEM_SIZE(type);
  const size_t channel_size = CV_ELEM_SIZE1(type);
  if (channel_size > 1 && image.is_bigendian != kHostIsBigEndian) {
    throw std::invalid_argument("image with encoding '" + image.encoding +
                                "' has a byte order other than the host's");
  }
  constexpr uint64_t kMaxDim = std::numeric_limits<int>::max();
  if (image.width > kMaxDim || image.height > kMaxDim) {
    throw std::invalid_argument("image dimensions " + std::to_string(image.width) + "x" +
                                std::to_string(image.height) + " are too large");
  }
  const uint64_t row_bytes = uint64_t{image.width} * element_size;
  if (image.step < row_bytes || image.step % channel_size != 0) {
    throw std::invalid_argument("image step " + std::to_string(image.step) + " does not fit " +
                                std::to_string(image.width) + " pixels of encoding '" +
                                image.encoding + "' (" + std::to_string(row_bytes) + " bytes)");
  }
  const uint64_t expected_bytes = uint64_t{image.step} * image.height;
  if (image.data.size() != expected_bytes) {
    throw std::invalid_argument("image data has " + std::to_string(image.data.size()) +
                                " bytes, step * height = " + std::to_string(expected_bytes));
  }
  if (image.width == 0 || image.height == 0) return cv::Mat();
  // cv::Mat takes a non-const pointer; the const overload of image_view documents read-only use.
  auto* data = const_cast<uint8_t*>(image.data.data());
  return cv::Mat(static_cast<int>(image.height), static_cast<int>(image.width), type, data,
                 image.step);
}

// The ROI of `info` in full-resolution pixels, all-zero meaning the full image.
cv::Rect full_resolution_roi(const msgs::CameraInfo& info) {
  const msgs::RegionOfInterest& roi = info.roi;
  if (roi.x_offset == 0 && roi.y_offset == 0 && roi.width == 0 && roi.height == 0) {
    return cv::Rect(0, 0, static_cast<int>(info.width), static_cast<int>(info.height));
  }
  if (roi.width == 0 || roi.height == 0 || uint64_t{roi.x_offset} + roi.width > info.width ||
      uint64_t{roi.y_offset} + roi.height > info.height) {
    throw std::invalid_argument("CameraInfo roi (x " + std::to_string(roi.x_offset) + ", y " +
                                std::to_string(roi.y_offset) + ", " + std::to_string(roi.width) +
                                "x" + std::to_string(roi.height) + ") is not inside the " +
                                std::to_string(info.width) + "x" + std::to_string(info.height) +
                                " image");
  }
  return cv::Rect(static_cast<int>(roi.x_offset), static_cast<int>(roi.y_offset),
                  static_cast<int>(roi.width), static_cast<int>(roi.height));
}

void require_distinct(const msgs::Image& in, const msgs::Image& out, const char* what) {
  if (&in == &out) {
    throw std::invalid_argument(std::string(what) + ": output image must not be the input image");
  }
}

// image_proc's static_cast<int>(value * scale) for sizes and offsets, range-checked.
uint32_t scaled_truncated(uint32_t value, double scale) {
  const double scaled = value * scale;
  if (!(scaled >= 0.0 && scaled < 2147483648.0)) {
    throw std::invalid_argument("resize: scaled camera size or offset " + std::to_string(scaled) +
                                " is out of range");
  }
  return static_cast<uint32_t>(static_cast<int>(scaled));
}

void copy_image(const msgs::Image& from, msgs::Image& to) {
  to.header = from.header;
  to.height = from.height;
  to.width = from.width;
  to.encoding = from.encoding;
  to.is_bigendian = from.is_bigendian;
  to.step = from.step;
  to.data.assign(from.data.begin(), from.data.end());
}

}  // namespace

int cv_type_from_encoding(std::string_view encoding) {
  if (encoding == "mono8") return CV_8UC1;
  if (encoding == "mono16") return CV_16UC1;
  if (encoding == "rgb8" || encoding == "bgr8") return CV_8UC3;
  if (encoding == "rgba8" || encoding == "bgra8") return CV_8UC4;
  if (encoding == "rgb16" || encoding == "bgr16") return CV_16UC3;
  if (encoding == "rgba16" || encoding == "bgra16") return CV_16UC4;
  if (encoding == "yuv422" || encoding == "uyvy" || encoding == "yuyv" ||
      encoding == "yuv422_yuy2") {
    return CV_8UC2;
  }
  if (starts_with_any(encoding, {"bayer_rggb", "bayer_bggr", "bayer_gbrg", "bayer_grbg"})) {
    const std::string_view bits = encoding.substr(std::string_view("bayer_rggb").size());
    if (bits == "8") return CV_8UC1;
    if (bits == "16") return CV_16UC1;
  }
  const int generic = cv_type_from_generic_name(encoding);
  if (generic >= 0) return generic;
  throw std::invalid_argument("unsupported image encoding '" + std::string(encoding) + "'");
}

cv::Mat image_view(msgs::Image& image) {
  return make_view(image);
}

cv::Mat image_view(const msgs::Image& image) {
  return make_view(image);
}

namespace {

// cvtColor's code from `encoding` to mono8; -1 for mono8 itself.
int mono8_conversion(const msgs::Image& image, const std::string& what) {
  if (image.encoding == "mono8" || image.encoding == "8UC1") return -1;
  if (image.encoding == "rgb8") return cv::COLOR_RGB2GRAY;
  if (image.encoding == "bgr8") return cv::COLOR_BGR2GRAY;
  if (image.encoding == "rgba8") return cv::COLOR_RGBA2GRAY;
  if (image.encoding == "bgra8") return cv::COLOR_BGRA2GRAY;
  throw std::invalid_argument(what + " encoding '" + image.encoding +
                              "' cannot be converted to mono8 (use mono8, rgb8, bgr8, rgba8 or "
                              "bgra8)");
}

}  // namespace

void to_mono8(const msgs::Image& image, const std::string& what, cv::Mat& mono) {
  const cv::Mat view = image_view(image);
  const int code = mono8_conversion(image, what);
  // A view of an earlier mono8 message is let go: converting into it would write the grey pixels
  // into that message, const and shared, or freed by now.
  if (mono.u == nullptr) mono.release();
  if (code < 0) {
    mono = view;
  } else {
    cv::cvtColor(view, mono, code);
  }
}

void write_mono8(const msgs::Image& image, const std::string& what, cv::Mat& into) {
  const cv::Mat view = image_view(image);
  const int code = mono8_conversion(image, what);
  if (into.type() != CV_8UC1 || into.size() != view.size()) {
    throw std::logic_error(what + ": the mono8 pixels' memory has another size");
  }
  const uchar* const memory = into.data;
  if (code < 0) {
    view.copyTo(into);
  } else {
    cv::cvtColor(view, into, code);
  }
  if (into.data != memory) throw std::logic_error(what + ": the mono8 pixels were moved");
}

cv::Mat prepare_image(msgs::Image& image, const msgs::Header& header, std::string_view encoding,
                      int width, int height) {
  const int type = cv_type_from_encoding(encoding);
  if (width < 0 || height < 0) {
    throw std::invalid_argument("negative image size " + std::to_string(width) + "x" +
                                std::to_string(height));
  }
  const uint64_t step = uint64_t(width) * CV_ELEM_SIZE(type);
  if (step > std::numeric_limits<uint32_t>::max()) {
    throw std::invalid_argument("image row of " + std::to_string(step) + " bytes is too long");
  }
  image.header = header;
  image.height = static_cast<uint32_t>(height);
  image.width = static_cast<uint32_t>(width);
  image.encoding.assign(encoding);
  image.is_bigendian = kHostIsBigEndian;
  image.step = static_cast<uint32_t>(step);
  image.data.resize(step * static_cast<uint64_t>(height));
  return image_view(image);
}

// ---------------------------------------------------------------------------------------------
// Rectifier
// ---------------------------------------------------------------------------------------------

namespace {

// A resident image's message holds its pixels in its deleter, where std::get_deleter finds them
// again through any shared_ptr (of any cv-qualification or aliasing) that shares its ownership.
struct ResidentImageDeleter {
  ResidentPixels pixels;
  void operator()(msgs::Image* image) const { delete image; }
};

}  // namespace

std::shared_ptr<const msgs::Image> resident_image_message(msgs::Image&& image,
                                                          ResidentPixels pixels) {
  image.data.clear();
  return std::shared_ptr<msgs::Image>(new msgs::Image(std::move(image)),
                                      ResidentImageDeleter{std::move(pixels)});
}

const ResidentPixels* resident_pixels(const std::shared_ptr<const msgs::Image>& message) {
  const auto* deleter = std::get_deleter<ResidentImageDeleter>(message);
  return deleter != nullptr ? &deleter->pixels : nullptr;
}

std::span<const RectifyImplementation> rectify_implementations() {
  static const RectifyImplementation table[] = {{"cpu", make_cpu_rectify},
                                                {"opencl", make_opencl_rectify, opencl_device},
                                                {"cuda", make_cuda_rectify, cuda_device, true}};
  return table;
}

Rectifier::Rectifier(int interpolation, std::string_view backend)
    : Rectifier(interpolation, implementation_on(rectify_implementations(), backend)) {}

Rectifier::Rectifier(int interpolation, const RectifyImplementation& backend)
    : interpolation_(interpolation), computation_(backend.make(interpolation)) {}

Rectifier::~Rectifier() = default;
Rectifier::Rectifier(Rectifier&&) noexcept = default;
Rectifier& Rectifier::operator=(Rectifier&&) noexcept = default;

bool Rectifier::MapInputs::matches(const msgs::CameraInfo& info) const {
  return width == info.width && height == info.height &&
         distortion_model == info.distortion_model && d == info.d && k == info.k && r == info.r &&
         p == info.p && binning_x == std::max<uint32_t>(info.binning_x, 1) &&
         binning_y == std::max<uint32_t>(info.binning_y, 1);
}

void Rectifier::update_maps(const msgs::CameraInfo& info) {
  const cv::Rect roi = full_resolution_roi(info);
  const bool full_maps_stale = !have_maps_ || !map_inputs_.matches(info);
  if (!full_maps_stale && roi == roi_) return;

  if (full_maps_stale) {
    MapInputs inputs{info.width,
                     info.height,
                     info.distortion_model,
                     info.d,
                     info.k,
                     info.r,
                     info.p,
                     std::max<uint32_t>(info.binning_x, 1),
                     std::max<uint32_t>(info.binning_y, 1)};
    const size_t d_size = inputs.d.size();
    const bool d_fits_model =
        (inputs.distortion_model == kPlumbBob && (d_size == 4 || d_size == 5)) ||
        (inputs.distortion_model == kRationalPolynomial && d_size == 8);
    if (!d_fits_model) {
      throw std::invalid_argument("cannot rectify distortion model '" + inputs.distortion_model +
                                  "' with " + std::to_string(d_size) +
                                  " coefficients (supported: plumb_bob with 4 or 5, "
                                  "rational_polynomial with 8)");
    }
    constexpr uint32_t kMaxDim = std::numeric_limits<int>::max();
    if (inputs.width == 0 || inputs.height == 0 || inputs.width > kMaxDim ||
        inputs.height > kMaxDim || inputs.binning_x > inputs.width ||
        inputs.binning_y > inputs.height) {
      throw std::invalid_argument("CameraInfo size " + std::to_string(inputs.width) + "x" +
                                  std::to_string(inputs.height) + " with binning " +
                                  std::to_string(inputs.binning_x) + "x" +
                                  std::to_string(inputs.binning_y) + " is invalid");
    }
    // The map is built at the binned resolution, with K and P scaled by the binning.
    cv::Matx33d k(inputs.k.data());
    cv::Matx34d p(inputs.p.data());
    const double x_scale = 1.0 / inputs.binning_x;
    const double y_scale = 1.0 / inputs.binning_y;
    if (inputs.binning_x > 1) {
      k(0, 0) *= x_scale;
      k(0, 2) *= x_scale;
      p(0, 0) *= x_scale;
      p(0, 2) *= x_scale;
      p(0, 3) *= x_scale;
    }
    if (inputs.binning_y > 1) {
      k(1, 1) *= y_scale;
      k(1, 2) *= y_scale;
      p(1, 1) *= y_scale;
      p(1, 2) *= y_scale;
      p(1, 3) *= y_scale;
    }
    const cv::Size binned_size(static_cast<int>(inputs.width / inputs.binning_x),
                               static_cast<int>(inputs.height / inputs.binning_y));
    const cv::Mat_<double> d(1, static_cast<int>(d_size), inputs.d.data());
    const cv::Matx33d r(inputs.r.data());
    have_maps_ = false;  // until the new maps are complete
    // Fixed-point maps (CV_16SC2 integer part + CV_16UC1 interpolation-table index) make remap
    // about twice as fast as float maps; image_geometry uses them too.
    cv::initUndistortRectifyMap(k, d, r, p, binned_size, CV_16SC2, full_map_xy_,
                                full_map_fraction_);
    ++map_computations_;
    map_inputs_ = std::move(inputs);
    have_maps_ = true;
  }

  roi_ = roi;
  if (roi == cv::Rect(0, 0, static_cast<int>(info.width), static_cast<int>(info.height))) {
    map_xy_ = full_map_xy_;
    map_fraction_ = full_map_fraction_;
  } else {
    const cv::Rect binned_roi(roi.x / static_cast<int>(map_inputs_.binning_x),
                              roi.y / static_cast<int>(map_inputs_.binning_y),
                              roi.width / static_cast<int>(map_inputs_.binning_x),
                              roi.height / static_cast<int>(map_inputs_.binning_y));
    if (binned_roi.empty()) {
      throw std::invalid_argument("CameraInfo roi is smaller than one binned pixel");
    }
    // The integer part of the map holds absolute source coordinates: make them relative to the
    // ROI; the fractional part is unchanged.
    cv::subtract(full_map_xy_(binned_roi), cv::Scalar(binned_roi.x, binned_roi.y), map_xy_);
    map_fraction_ = full_map_fraction_(binned_roi).clone();
  }
  computation_->set_maps(map_xy_, map_fraction_);
}

bool Rectifier::prepare(const msgs::Image& raw, const msgs::CameraInfo& info,
                        msgs::Image& rectified) {
  require_distinct(raw, rectified, "rectify");
  if (info.k[0] == 0.0) {
    throw std::invalid_argument("rectify: camera is uncalibrated (CameraInfo K[0] == 0)");
  }
  const cv::Mat raw_view = image_view(raw);
  if (std::all_of(info.d.begin(), info.d.end(), [](double c) { return c == 0.0; })) {
    copy_image(raw, rectified);
    return false;
  }
  update_maps(info);
  if (raw_view.size() != map_xy_.size()) {
    throw std::invalid_argument("rectify: image is " + std::to_string(raw.width) + "x" +
                                std::to_string(raw.height) +
                                " but its CameraInfo (size, binning, roi) gives " +
                                std::to_string(map_xy_.cols) + "x" + std::to_string(map_xy_.rows));
  }
  return true;
}

std::optional<ResidentPixels> Rectifier::rectify_on_device(const msgs::Image& raw,
                                                           const msgs::CameraInfo& info,
                                                           msgs::Image& rectified) {
  if (!prepare(raw, info, rectified)) return std::nullopt;
  // The rectified message's header, size and encoding, without its pixels.
  prepare_image(rectified, raw.header, raw.encoding, 0, 0);
  rectified.height = raw.height;
  rectified.width = raw.width;
  rectified.step =
      raw.width * static_cast<uint32_t>(CV_ELEM_SIZE(cv_type_from_encoding(raw.encoding)));
  return computation_->remap_to_device(image_view(raw));
}

void Rectifier::rectify(const msgs::Image& raw, const msgs::CameraInfo& info,
                        msgs::Image& rectified) {
  if (!prepare(raw, info, rectified)) return;
  // The output message is made while a device works.
  computation_->remap(image_view(raw), raw.encoding, [&] {
    return prepare_image(rectified, raw.header, raw.encoding, static_cast<int>(raw.width),
                         static_cast<int>(raw.height));
  });
}

msgs::Image Rectifier::rectify(const msgs::Image& raw, const msgs::CameraInfo& info) {
  msgs::Image rectified;
  rectify(raw, info, rectified);
  return rectified;
}

// ---------------------------------------------------------------------------------------------
// Resize
// ---------------------------------------------------------------------------------------------

std::span<const ResizeImplementation> resize_implementations() {
  static const ResizeImplementation table[] = {{"cpu", make_cpu_resize},
                                               {"opencl", make_opencl_resize, opencl_device},
                                               {"cuda", make_cuda_resize, cuda_device, true}};
  return table;
}

Resizer::Resizer(const ResizeParams& params, std::string_view backend)
    : Resizer(params, implementation_on(resize_implementations(), backend)) {}

Resizer::Resizer(const ResizeParams& params, const ResizeImplementation& backend)
    : params_(params), computation_(backend.make(params)) {}

Resizer::~Resizer() = default;
Resizer::Resizer(Resizer&&) noexcept = default;
Resizer& Resizer::operator=(Resizer&&) noexcept = default;

void Resizer::resize(const msgs::Image& image, const msgs::CameraInfo& info, msgs::Image& out,
                     msgs::CameraInfo& out_info, const ResidentPixels* pixels) {
  require_distinct(image, out, "resize");
  const ResizeParams& params = params_;
  cv::Mat in_view;
  cv::Size in_size;
  if (pixels != nullptr) {
    if (pixels->cols != static_cast<int64_t>(image.width) ||
        pixels->rows != static_cast<int64_t>(image.height) ||
        pixels->type != cv_type_from_encoding(image.encoding)) {
      throw std::invalid_argument(
          "resize: the pixels on the device are not of the image's size "
          "and encoding");
    }
    in_size = cv::Size(pixels->cols, pixels->rows);
  } else {
    in_view = image_view(image);
    in_size = in_view.size();
  }
  if (in_size.empty()) throw std::invalid_argument("resize: empty image");

  double scale_x = 0.0;
  double scale_y = 0.0;
  cv::Size out_size;
  uint32_t info_width = 0;
  uint32_t info_height = 0;
  if (params.use_scale) {
    if (!(params.scale_width > 0.0) || !(params.scale_height > 0.0)) {
      throw std::invalid_argument("resize: scale_width and scale_height must be positive");
    }
    scale_x = params.scale_width;
    scale_y = params.scale_height;
    // cv::resize's own rounding of a scaled size, so that the destination is not reallocated.
    out_size = cv::Size(cv::saturate_cast<int>(in_size.width * scale_x),
                        cv::saturate_cast<int>(in_size.height * scale_y));
    info_width = scaled_truncated(info.width, scale_x);
    info_height = scaled_truncated(info.height, scale_y);
  } else {
    if ((params.width <= 0 && params.width != -1) || (params.height <= 0 && params.height != -1)) {
      throw std::invalid_argument("resize: width and height must be positive or -1");
    }
    out_size = cv::Size(params.width == -1 ? in_size.width : params.width,
                        params.height == -1 ? in_size.height : params.height);
    if (info.width == 0 || info.height == 0) {
      throw std::invalid_argument("resize: CameraInfo has zero size");
    }
    scale_x = static_cast<double>(out_size.width) / info.width;
    scale_y = static_cast<double>(out_size.height) / info.height;
    info_width = static_cast<uint32_t>(out_size.width);
    info_height = static_cast<uint32_t>(out_size.height);
  }
  if (out_size.empty()) throw std::invalid_argument("resize: output would be empty");
  // The inverse scales cv::resize computes with: those given, or the sizes' ratios.
  const double inv_scale_x =
      params.use_scale ? scale_x : static_cast<double>(out_size.width) / in_size.width;
  const double inv_scale_y =
      params.use_scale ? scale_y : static_cast<double>(out_size.height) / in_size.height;
  const ResizeShape shape{in_size, out_size, inv_scale_x, inv_scale_y, params.use_scale};
  // The output message is made while a device works; the computation writes into its pixels.
  const auto make_output = [&] {
    return prepare_image(out, image.header, image.encoding, out_size.width, out_size.height);
  };
  if (pixels != nullptr) {
    computation_->resize(*pixels, shape, make_output);
  } else {
    computation_->resize(in_view, image.encoding, shape, make_output);
  }

  out_info = info;
  out_info.width = info_width;
  out_info.height = info_height;
  out_info.k[0] *= scale_x;  // fx
  out_info.k[2] *= scale_x;  // cx
  out_info.k[4] *= scale_y;  // fy
  out_info.k[5] *= scale_y;  // cy
  out_info.p[0] *= scale_x;  // fx'
  out_info.p[2] *= scale_x;  // cx'
  out_info.p[3] *= scale_x;  // Tx = -fx' * baseline
  out_info.p[5] *= scale_y;  // fy'
  out_info.p[6] *= scale_y;  // cy'
  out_info.roi.x_offset = scaled_truncated(info.roi.x_offset, scale_x);
  out_info.roi.y_offset = scaled_truncated(info.roi.y_offset, scale_y);
  out_info.roi.width = scaled_truncated(info.roi.width, scale_x);
  out_info.roi.height = scaled_truncated(info.roi.height, scale_y);
}

void resize(const msgs::Image& image, const msgs::CameraInfo& info, const ResizeParams& params,
            msgs::Image& out, msgs::CameraInfo& out_info, std::string_view backend) {
  Resizer(params, backend).resize(image, info, out, out_info);
}

// ---------------------------------------------------------------------------------------------
// What the backends' implementations share
// ---------------------------------------------------------------------------------------------

ResidentPixels RectifyComputation::remap_to_device(const cv::Mat& /*raw*/) {
  throw std::logic_error("rectify: only the cuda backend leaves images on the device");
}

void ResizeComputation::resize(const ResidentPixels& /*in*/, const ResizeShape& /*shape*/,
                               const std::function<cv::Mat()>& /*make_output*/) {
  throw std::logic_error("resize: only the cuda backend takes images left on the device");
}

void require_interpolation_in_range(int interpolation) {
  if (interpolation < cv::INTER_NEAREST || interpolation > cv::INTER_LANCZOS4) {
    throw std::invalid_argument("interpolation " + std::to_string(interpolation) +
                                " is not one of INTER_NEAREST(0) .. INTER_LANCZOS4(4)");
  }
}

void resize_as(cv::InputArray in, cv::OutputArray out, const ResizeShape& shape,
               int interpolation) {
  if (shape.given_scales) {
    cv::resize(in, out, cv::Size(), shape.inv_scale_x, shape.inv_scale_y, interpolation);
  } else {
    cv::resize(in, out, shape.out_size, 0.0, 0.0, interpolation);
  }
}

cv::Scalar remap_border(int depth) {
  const bool is_float = depth == CV_32F || depth == CV_64F;
  return cv::Scalar::all(is_float ? std::numeric_limits<float>::quiet_NaN() : 0.0);
}

}  // namespace robotperf::perception
