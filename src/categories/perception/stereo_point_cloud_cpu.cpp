// The stereo point cloud on the host CPU, with OpenCV's reprojectImageTo3D as image_geometry calls
// it: the cpu backend of stereo_point_cloud_computations.hpp.
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/calib3d.hpp>

#include "stereo_point_cloud_computations.hpp"

namespace robotperf::perception {
namespace {

class CpuStereoPointCloud final : public StereoPointCloudComputation {
 public:
  void points(const cv::Mat& disparity, const cv::Mat& left, const StereoCloudModel& model,
              msgs::PointCloud2& cloud) override {
    cv::reprojectImageTo3D(disparity, xyz_, model.q, true);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    uint8_t* out = cloud.data.data();
    for (int v = 0; v < xyz_.rows; ++v) {
      const cv::Vec3f* row = xyz_.ptr<cv::Vec3f>(v);
      const uint8_t* px = model.colour ? left.ptr<uint8_t>(v) : nullptr;
      for (int u = 0; u < xyz_.cols; ++u, out += model.point_step) {
        const cv::Vec3f& p = row[u];
        // PointCloudNode's isValidPoint: neither a missing disparity nor a zero one.
        const bool valid = p[2] != kMissingZ && !std::isinf(p[2]);
        const float xyz[3] = {valid ? p[0] : nan, valid ? p[1] : nan, valid ? p[2] : nan};
        std::memcpy(out, xyz, sizeof xyz);
        if (!model.colour) continue;
        uint8_t* rgb = out + model.rgb_offset;
        rgb[0] = px[model.blue];
        rgb[1] = px[model.green];
        rgb[2] = px[model.red];
        px += model.colour_bytes;
      }
    }
  }

 private:
  cv::Mat xyz_;
};

}  // namespace

std::unique_ptr<StereoPointCloudComputation> make_cpu_stereo_point_cloud() {
  return std::make_unique<CpuStereoPointCloud>();
}

}  // namespace robotperf::perception
