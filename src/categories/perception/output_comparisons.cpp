// The perception category's comparisons of a backend's answers with the cpu's (docs/design.md
// §6), for the message types its kernels answer with: images, point clouds and disparity
// images.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include "category.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"
#include "robotperf/msgs/stereo_msgs.hpp"

namespace robotperf::perception {
namespace {

// |a - b| <= tolerance, NaN agreeing only with NaN.
template <class T>
bool close(T a, T b, double tolerance) {
  if constexpr (std::is_floating_point_v<T>) {
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
    if (a == b) return true;  // equal infinities, whose difference is NaN
  }
  return std::abs(static_cast<double>(a) - static_cast<double>(b)) <= tolerance;
}

template <class T>
T element(const uint8_t* bytes, std::size_t i) {
  T value;
  std::memcpy(&value, bytes + i * sizeof(T), sizeof(T));
  return value;
}

template <class T>
double share_close(const uint8_t* a, const uint8_t* b, std::size_t bytes, double tolerance) {
  const std::size_t n = bytes / sizeof(T);
  if (n == 0) return 1.0;
  std::size_t within = 0;
  for (std::size_t i = 0; i < n; ++i)
    within += close(element<T>(a, i), element<T>(b, i), tolerance) ? 1 : 0;
  return static_cast<double>(within) / static_cast<double>(n);
}

// One level of an integer channel. A float channel has no level (it may be depth in metres, where
// 1 would pass nearly any answer): 1e-4 of the reference's largest finite magnitude, which leaves
// room for a device computing its sample coordinates in float (OpenCL's resize: 2e-5 on 0..1).
constexpr double kIntegerChannelLevels = 1.0;
constexpr double kFloatChannelShareOfMagnitude = 1e-4;

// The type of one channel of an image's pixels.
enum class Channel { kU8, kS8, kU16, kS16, kS32, kF32, kF64 };

// The channel type of an encoding of sensor_msgs/image_encodings: a named one (mono8, rgb16,
// bayer_rggb8, yuv422, ...) or "<bits><U|S|F>C<channels>" (8UC3, 16SC1, 32FC1, ...). nullopt for
// one it does not name: its bytes say nothing comparable.
std::optional<Channel> channel_of(std::string_view encoding) {
  for (std::string_view name :
       {"mono8", "rgb8", "bgr8", "rgba8", "bgra8", "bayer_rggb8", "bayer_bggr8", "bayer_gbrg8",
        "bayer_grbg8", "yuv422", "uyvy", "yuyv", "yuv422_yuy2"}) {
    if (encoding == name) return Channel::kU8;
  }
  for (std::string_view name : {"mono16", "rgb16", "bgr16", "rgba16", "bgra16", "bayer_rggb16",
                                "bayer_bggr16", "bayer_gbrg16", "bayer_grbg16"}) {
    if (encoding == name) return Channel::kU16;
  }
  const std::size_t c = encoding.find('C');
  if (c == std::string_view::npos) return std::nullopt;
  const std::string_view digits = encoding.substr(c + 1);
  int channels = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), channels);
  if (digits.empty() || error != std::errc() || end != digits.data() + digits.size() ||
      channels < 1) {
    return std::nullopt;
  }
  const std::string_view depth = encoding.substr(0, c);
  if (depth == "8U") return Channel::kU8;
  if (depth == "8S") return Channel::kS8;
  if (depth == "16U") return Channel::kU16;
  if (depth == "16S") return Channel::kS16;
  if (depth == "32S") return Channel::kS32;
  if (depth == "32F") return Channel::kF32;
  if (depth == "64F") return Channel::kF64;
  return std::nullopt;
}

template <class T>
double float_share(const uint8_t* a, const uint8_t* reference, std::size_t bytes) {
  double magnitude = 0.0;
  for (std::size_t i = 0; i < bytes / sizeof(T); ++i) {
    const double v = std::abs(static_cast<double>(element<T>(reference, i)));
    if (std::isfinite(v)) magnitude = std::max(magnitude, v);
  }
  return share_close<T>(a, reference, bytes, kFloatChannelShareOfMagnitude * magnitude);
}

// Channel by channel, as the encoding's channel type; nothing agrees in an encoding it cannot
// read.
double image_share(const msgs::Image& a, const msgs::Image& b) {
  if (a.width != b.width || a.height != b.height || a.encoding != b.encoding || a.step != b.step ||
      a.data.size() != b.data.size()) {
    return 0.0;
  }
  const std::optional<Channel> channel = channel_of(a.encoding);
  if (!channel) return 0.0;
  const uint8_t* x = a.data.data();
  const uint8_t* y = b.data.data();
  const std::size_t bytes = a.data.size();
  switch (*channel) {
    case Channel::kU8:
      return share_close<uint8_t>(x, y, bytes, kIntegerChannelLevels);
    case Channel::kS8:
      return share_close<int8_t>(x, y, bytes, kIntegerChannelLevels);
    case Channel::kU16:
      return share_close<uint16_t>(x, y, bytes, kIntegerChannelLevels);
    case Channel::kS16:
      return share_close<int16_t>(x, y, bytes, kIntegerChannelLevels);
    case Channel::kS32:
      return share_close<int32_t>(x, y, bytes, kIntegerChannelLevels);
    case Channel::kF32:
      return float_share<float>(x, y, bytes);
    case Channel::kF64:
      return float_share<double>(x, y, bytes);
  }
  return 0.0;
}

std::string image_criterion(const std::string& encoding) {
  const std::optional<Channel> channel = channel_of(encoding);
  if (!channel) {
    return "pixels of a known encoding ('" + encoding +
           "' is not one of sensor_msgs/image_encodings, so nothing is compared)";
  }
  if (*channel == Channel::kF32 || *channel == Channel::kF64)
    return "|difference| <= 1e-4 x the cpu image's largest |value| on float pixel channels";
  return "|difference| <= 1 on pixel channels";
}

double cloud_share(const msgs::PointCloud2& a, const msgs::PointCloud2& b) {
  if (a.width != b.width || a.height != b.height || a.fields != b.fields ||
      a.point_step != b.point_step || a.data.size() != b.data.size() || a.point_step == 0) {
    return 0.0;
  }
  const std::size_t points = a.data.size() / a.point_step;
  if (points == 0) return 1.0;
  std::size_t agree = 0;
  for (std::size_t p = 0; p < points; ++p) {
    const uint8_t* x = a.data.data() + p * a.point_step;
    const uint8_t* y = b.data.data() + p * b.point_step;
    bool same = true;
    for (const auto& f : a.fields) {
      const std::size_t size = f.datatype == msgs::PointField::kFloat64  ? 8
                               : f.datatype <= msgs::PointField::kUint8  ? 1
                               : f.datatype <= msgs::PointField::kUint16 ? 2
                                                                         : 4;
      for (uint32_t c = 0; c < std::max<uint32_t>(f.count, 1) && same; ++c) {
        const std::size_t at = f.offset + c * size;
        if (at + size > a.point_step) {
          same = false;
        } else if ((f.name == "rgb" || f.name == "rgba") && size == 4) {
          // Packed colour bytes, whatever the declared type (PCL's is FLOAT32, whose bytes read
          // as a float are tiny or denormal and would always agree): one level per channel, as
          // for images.
          same = share_close<uint8_t>(x + at, y + at, size, 1.0) == 1.0;
        } else if (f.datatype == msgs::PointField::kFloat32) {
          same = share_close<float>(x + at, y + at, size, 1e-6) == 1.0;
        } else if (f.datatype == msgs::PointField::kFloat64) {
          same = share_close<double>(x + at, y + at, size, 1e-6) == 1.0;
        } else {
          same = std::memcmp(x + at, y + at, size) == 0;
        }
      }
    }
    agree += same ? 1 : 0;
  }
  return static_cast<double>(agree) / static_cast<double>(points);
}

// The node gives every pixel it finds no disparity for one value, min_disparity - 1 less the x
// offset of the two principal points (it takes the offset off every pixel, as ROS's
// stereo_image_proc does), and the message does not carry that offset. Every disparity it finds
// is at least 1 above that value, so the value is the smallest of the cpu's answer, as ROS's
// point cloud node finds it (cv::reprojectImageTo3D's missing values); both answers are to the
// same inputs, so it is the same offset on both sides. A pixel is valid on a side where it is
// finite and more than half a pixel above that value. Of the pixels valid on either side, the
// share valid on both and within 1 px: one the other backend leaves out, or keeps where the cpu
// filtered it (texture, uniqueness, speckles), disagrees.
double disparity_share(const msgs::DisparityImage& accelerated, const msgs::DisparityImage& cpu) {
  const msgs::Image& a = accelerated.image;
  const msgs::Image& c = cpu.image;
  if (a.width != c.width || a.height != c.height || a.encoding != "32FC1" ||
      c.encoding != "32FC1" || a.data.size() != c.data.size()) {
    return 0.0;
  }
  const std::size_t n = c.data.size() / sizeof(float);
  float invalid = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const float y = element<float>(c.data.data(), i);
    if (std::isfinite(y)) invalid = std::min(invalid, y);
  }
  // A cpu answer with no disparity at all: any the other backend finds disagrees.
  if (!std::isfinite(invalid)) invalid = -std::numeric_limits<float>::infinity();
  const auto valid = [&](float d) { return std::isfinite(d) && d > invalid + 0.5f; };
  std::size_t either = 0, within = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float x = element<float>(a.data.data(), i), y = element<float>(c.data.data(), i);
    if (!valid(x) && !valid(y)) continue;
    ++either;
    within += valid(x) && valid(y) && std::abs(x - y) <= 1.0f ? 1 : 0;
  }
  return either == 0 ? 1.0 : static_cast<double>(within) / static_cast<double>(either);
}

constexpr const char* kCloudCriterion =
    "points with every float field within 1e-6, the rest identical";
constexpr const char* kDisparityCriterion =
    "pixels with a disparity on either backend that have one on both, within 1 px";

}  // namespace

void register_output_comparisons(plugin::Registrar& registrar) {
  // Images: each channel read as its encoding's type (sensor_msgs/image_encodings), on >= 99.9 %
  // (the two backends may round a bilinear tap differently); an encoding it cannot read agrees
  // nowhere.
  registrar.add_output_comparison(
      {.ros_type = std::string(msgs::MessageTraits<msgs::Image>::ros_type),
       .description = "pixel channels within one level (integer) or 1e-4 of the cpu image's "
                      "largest value (float)"},
      [](const void* accelerated, const void* cpu) {
        const auto& cpu_image = *static_cast<const msgs::Image*>(cpu);
        return plugin::Agreement{
            image_share(*static_cast<const msgs::Image*>(accelerated), cpu_image), 0.999,
            image_criterion(cpu_image.encoding)};
      });
  // Point clouds: every point's float fields within 1e-6 (m) or both NaN, other fields identical.
  registrar.add_output_comparison(
      {.ros_type = std::string(msgs::MessageTraits<msgs::PointCloud2>::ros_type),
       .description = kCloudCriterion},
      [](const void* accelerated, const void* cpu) {
        return plugin::Agreement{cloud_share(*static_cast<const msgs::PointCloud2*>(accelerated),
                                             *static_cast<const msgs::PointCloud2*>(cpu)),
                                 1.0, kCloudCriterion};
      });
  // Disparity images: of the pixels with a disparity on either backend, >= 95 % with one on both
  // within 1 px.
  registrar.add_output_comparison(
      {.ros_type = std::string(msgs::MessageTraits<msgs::DisparityImage>::ros_type),
       .description = kDisparityCriterion},
      [](const void* accelerated, const void* cpu) {
        return plugin::Agreement{
            disparity_share(*static_cast<const msgs::DisparityImage*>(accelerated),
                            *static_cast<const msgs::DisparityImage*>(cpu)),
            0.95, kDisparityCriterion};
      });
}

}  // namespace robotperf::perception
