#include "robotperf/perception/stereo_point_cloud.hpp"

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "colour_layout.hpp"
#include "robotperf/perception/opencl_device.hpp"
#include "stereo_point_cloud_computations.hpp"

namespace robotperf::perception {
namespace {

const std::string kWhat = "stereo point cloud";

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(kWhat + ": " + what);
}

// image_geometry's StereoCameraModel::updateQ (ROS 2), from the P matrices as it reads them.
cv::Matx44d reprojection(const msgs::CameraInfo& left, const msgs::CameraInfo& right) {
  const double fx = left.p[0], fy = left.p[5], cx = left.p[2], cy = left.p[6];
  const double tx = right.p[3] / right.p[0];  // -baseline
  cv::Matx44d q = cv::Matx44d::zeros();
  q(0, 0) = fy * tx;
  q(0, 3) = -fy * cx * tx;
  q(1, 1) = fx * tx;
  q(1, 3) = -fx * cy * tx;
  q(2, 3) = fx * fy * tx;
  q(3, 2) = -fy;
  q(3, 3) = fy * (cx - right.p[2]);
  return q;
}

}  // namespace

std::span<const StereoPointCloudImplementation> stereo_point_cloud_implementations() {
  static const StereoPointCloudImplementation table[] = {
      {"cpu", make_cpu_stereo_point_cloud},
      {"opencl", make_opencl_stereo_point_cloud, opencl_device}};
  return table;
}

StereoPointCloudProcessor::StereoPointCloudProcessor(std::string_view backend)
    : StereoPointCloudProcessor(implementation_on(stereo_point_cloud_implementations(), backend)) {}

StereoPointCloudProcessor::StereoPointCloudProcessor(const StereoPointCloudImplementation& backend)
    : computation_(backend.make()) {}

StereoPointCloudProcessor::~StereoPointCloudProcessor() = default;
StereoPointCloudProcessor::StereoPointCloudProcessor(StereoPointCloudProcessor&&) noexcept =
    default;
StereoPointCloudProcessor& StereoPointCloudProcessor::operator=(
    StereoPointCloudProcessor&&) noexcept = default;

void StereoPointCloudProcessor::compute(const msgs::Image& left_image,
                                        const msgs::CameraInfo& left_info,
                                        const msgs::CameraInfo& right_info,
                                        const msgs::DisparityImage& disparity,
                                        const StereoPointCloudParams& params,
                                        msgs::PointCloud2& cloud) {
  const msgs::Image& d = disparity.image;
  require(d.encoding == "32FC1",
          "disparity encoding '" + d.encoding + "' is not 32FC1 (stereo_msgs/DisparityImage)");
  require(left_info.p[0] != 0.0 && left_info.p[5] != 0.0,
          "left CameraInfo has no focal length (P[0], P[5])");
  require(right_info.p[0] != 0.0 && right_info.p[3] != 0.0,
          "right CameraInfo has no focal length or baseline (P[0], P[3])");
  StereoCloudModel model;
  model.q = reprojection(left_info, right_info);
  model.colour = params.use_color;
  if (model.colour) {
    require(left_image.width == d.width && left_image.height == d.height,
            "left image is " + std::to_string(left_image.width) + "x" +
                std::to_string(left_image.height) + ", the disparity " + std::to_string(d.width) +
                "x" + std::to_string(d.height));
    const ColourLayout layout = colour_layout(left_image.encoding, kWhat);
    model.red = layout.red;
    model.green = layout.green;
    model.blue = layout.blue;
    model.colour_bytes = layout.step;
  }
  const cv::Mat disparity_view = image_view(d);
  const cv::Mat left_view = model.colour ? image_view(left_image) : cv::Mat();

  // PointCloud2Modifier aligns each field to its size and the point to 16 bytes; without padding
  // the fields follow one another.
  const bool packed = params.avoid_point_cloud_padding;
  model.rgb_offset = packed ? 12 : 16;
  model.point_step = model.colour ? (packed ? 16 : 32) : (packed ? 12 : 16);
  cloud.header = disparity.header;
  cloud.height = d.height;
  cloud.width = d.width;
  cloud.is_bigendian = false;
  cloud.is_dense = false;
  cloud.point_step = static_cast<uint32_t>(model.point_step);
  cloud.row_step = cloud.point_step * d.width;
  constexpr uint8_t kFloat32 = msgs::PointField::kFloat32;
  std::vector<msgs::PointField> fields = {
      {"x", 0, kFloat32, 1}, {"y", 4, kFloat32, 1}, {"z", 8, kFloat32, 1}};
  if (model.colour) fields.push_back({"rgb", static_cast<uint32_t>(model.rgb_offset), kFloat32, 1});
  // Padding and the fourth colour byte are zero from the allocation: a cloud of the same size and
  // fields is reused without clearing.
  const std::size_t bytes = static_cast<std::size_t>(cloud.row_step) * d.height;
  if (cloud.data.size() != bytes || cloud.fields != fields) cloud.data.assign(bytes, 0);
  cloud.fields = std::move(fields);
  if (disparity_view.empty()) return;
  computation_->points(disparity_view, left_view, model, cloud);
}

}  // namespace robotperf::perception
