// The point cloud on the host CPU, as depth_image_proc computes it: the cpu backend of
// depth_image_proc_computations.hpp.
#include <cstring>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "depth_image_proc_computations.hpp"

namespace robotperf::perception {
namespace {

template <class T>
void convert_depth(const cv::Mat& depth, const XyzrgbModel& m, msgs::PointCloud2& cloud) {
  using Traits = DepthTraits<T>;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // The fill in the depth's own unit (a whole number of millimetres for 16UC1).
  const T fill = static_cast<T>(m.fill);
  uint8_t* out = cloud.data.data();
  for (int v = 0; v < depth.rows; ++v) {
    const T* row = depth.ptr<T>(v);
    for (int u = 0; u < depth.cols; ++u, out += kXyzrgbPointStep) {
      T d = row[u];
      float xyz[3];
      if (!Traits::valid(d) && !m.fill_invalid) {
        xyz[0] = xyz[1] = xyz[2] = nan;
      } else {
        if (!Traits::valid(d)) d = fill;
        xyz[0] = (static_cast<float>(u) - m.cx) * d * m.constant_x;
        xyz[1] = (static_cast<float>(v) - m.cy) * d * m.constant_y;
        xyz[2] = Traits::to_metres(d);
      }
      std::memcpy(out + kXyzrgbOffsetX, xyz, sizeof xyz);
    }
  }
}

void convert_colour(const cv::Mat& colour, const XyzrgbModel& m, msgs::PointCloud2& cloud) {
  uint8_t* out = cloud.data.data() + kXyzrgbOffsetRgb;
  for (int v = 0; v < colour.rows; ++v) {
    const uint8_t* px = colour.ptr<uint8_t>(v);
    for (int u = 0; u < colour.cols; ++u, px += m.colour_bytes, out += kXyzrgbPointStep) {
      // Packed as PointCloud2Iterator's "b", "g", "r" views of the rgb field place them.
      out[0] = px[m.blue];
      out[1] = px[m.green];
      out[2] = px[m.red];
    }
  }
}

class CpuPointCloud final : public PointCloudComputation {
 public:
  void xyzrgb(const cv::Mat& depth, const cv::Mat& colour, const XyzrgbModel& model,
              msgs::PointCloud2& cloud) override {
    if (model.metres) {
      convert_depth<float>(depth, model, cloud);
    } else {
      convert_depth<uint16_t>(depth, model, cloud);
    }
    if (colour.size() == depth.size()) {
      convert_colour(colour, model, cloud);
      return;
    }
    cv::resize(colour, resized_colour_, depth.size(), 0, 0, cv::INTER_LINEAR);
    convert_colour(resized_colour_, model, cloud);
  }

 private:
  cv::Mat resized_colour_;
};

}  // namespace

std::unique_ptr<PointCloudComputation> make_cpu_point_cloud() {
  return std::make_unique<CpuPointCloud>();
}

}  // namespace robotperf::perception
