// Private to the perception category: what the device kernels of point_cloud_xyzrgb need to
// compute a point, as the cpu computes it. Plain data, free of OpenCV, so that CUDA's device code
// can include it.
#pragma once

namespace robotperf::perception {

struct XyzrgbModel {
  bool metres = false;  // 32FC1 depth in metres; else 16UC1 in millimetres
  // The depth image's principal point (px), and the depth unit in metres over the focal lengths.
  float cx = 0, cy = 0, constant_x = 0, constant_y = 0;
  // Invalid depth becomes `fill` (in the depth's unit) when set, else a NaN point.
  bool fill_invalid = false;
  float fill = 0;
  // Byte offsets of red, green and blue in a colour pixel, and its size in bytes.
  int red = 0, green = 0, blue = 0, colour_bytes = 0;
};

}  // namespace robotperf::perception
