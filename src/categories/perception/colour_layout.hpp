// Private to the perception category: where red, green and blue lie in a pixel of the 8-bit
// colour encodings the point cloud kernels take.
#pragma once

#include <stdexcept>
#include <string>

namespace robotperf::perception {

// Byte offsets of red, green and blue in a pixel, and its size in bytes.
struct ColourLayout {
  int red, green, blue, step;
};

// Throws std::invalid_argument, starting with `what`, for an encoding other than rgb8, rgba8,
// bgr8, bgra8 or mono8 (whose one byte is all three).
inline ColourLayout colour_layout(const std::string& encoding, const std::string& what) {
  if (encoding == "rgb8") return {0, 1, 2, 3};
  if (encoding == "rgba8") return {0, 1, 2, 4};
  if (encoding == "bgr8") return {2, 1, 0, 3};
  if (encoding == "bgra8") return {2, 1, 0, 4};
  if (encoding == "mono8") return {0, 0, 0, 1};
  throw std::invalid_argument(what + ": colour encoding '" + encoding +
                              "' is not supported (rgb8, rgba8, bgr8, bgra8, mono8)");
}

}  // namespace robotperf::perception
