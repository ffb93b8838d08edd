// depthimage_to_laserscan and pointcloud_to_laserscan as graph nodes.
#include <memory>
#include <stdexcept>

#include "category.hpp"
#include "robotperf/perception/laser_scan.hpp"
#include "skipping_node.hpp"

namespace robotperf::perception {
namespace {

using plugin::KernelConfig;

const DepthToScanParams kDepthToScan;
const plugin::ParameterStruct<DepthToScanParams> kDepthToScanParameters{
    plugin::field(&DepthToScanParams::scan_time, "scan_time", kDepthToScan.scan_time,
                  "time between scans, s, copied into the scan"),
    plugin::field(&DepthToScanParams::range_min, "range_min", kDepthToScan.range_min,
                  "shortest range kept, m"),
    plugin::field(&DepthToScanParams::range_max, "range_max", kDepthToScan.range_max,
                  "longest range kept, m"),
    plugin::field(&DepthToScanParams::scan_height, "scan_height", kDepthToScan.scan_height,
                  "rows about the principal point whose per-column minimum is the scan",
                  {.minimum = 1}),
    plugin::field(&DepthToScanParams::output_frame, "output_frame", kDepthToScan.output_frame,
                  "frame_id of the scan; empty keeps the depth image's")};

// DepthImageToLaserScanROS: each depth image is converted with the latest CameraInfo, not one
// paired with it by stamp; images before the first CameraInfo are dropped and counted.
class DepthToScanNode final : public SkippingNode {
 public:
  DepthToScanNode(graph::Context& context, const KernelConfig& config)
      : SkippingNode(context, config.node_name),
        params_(kDepthToScanParameters.read(config.parameters)) {
    output_ = create_publisher<msgs::LaserScan>(config.topic("scan"), config.qos);
    info_sub_ = create_subscription<msgs::CameraInfo>(
        config.topic("depth_camera_info"), config.qos,
        [this](std::shared_ptr<const msgs::CameraInfo> info) { info_ = std::move(info); });
    depth_sub_ = create_subscription<msgs::Image>(
        config.topic("depth"), config.qos,
        [this](std::shared_ptr<const msgs::Image> depth) { convert(*depth); });
  }

  std::map<std::string, uint64_t> counters() const override {
    return {{"images_without_camera_info", images_without_info_},
            {"rejected_images", rejected_.count()}};
  }

 private:
  void convert(const msgs::Image& depth) {
    if (!info_) {
      ++images_without_info_;
      return;
    }
    guarded([&] {
      plugin::trace_kernel_init(*this, kKernel, depth.header.stamp.to_ns(), depth, *info_);
      auto scan = std::make_shared<msgs::LaserScan>();
      depth_image_to_laser_scan(depth, *info_, params_, *scan);
      plugin::trace_kernel_fini(*this, kKernel, *scan);
      output_->publish(std::shared_ptr<const msgs::LaserScan>(std::move(scan)));
    });
  }

  static constexpr const char* kKernel = "depthimage_to_laserscan/convert";
  DepthToScanParams params_;
  std::shared_ptr<const msgs::CameraInfo> info_;
  uint64_t images_without_info_ = 0;
  std::shared_ptr<graph::Publisher<msgs::LaserScan>> output_;
  std::shared_ptr<graph::GenericSubscription> info_sub_, depth_sub_;
};

const CloudToScanParams kCloudToScan;
const plugin::ParameterStruct<CloudToScanParams> kCloudToScanParameters{
    plugin::field(&CloudToScanParams::target_frame, "target_frame", kCloudToScan.target_frame,
                  "frame of the scan; empty = the cloud's (no tf here: another frame is refused)"),
    plugin::field(&CloudToScanParams::min_height, "min_height", kCloudToScan.min_height,
                  "lowest z of a point kept, m"),
    plugin::field(&CloudToScanParams::max_height, "max_height", kCloudToScan.max_height,
                  "highest z of a point kept, m"),
    plugin::field(&CloudToScanParams::angle_min, "angle_min", kCloudToScan.angle_min,
                  "angle of the first beam, rad"),
    plugin::field(&CloudToScanParams::angle_max, "angle_max", kCloudToScan.angle_max,
                  "largest angle kept, rad"),
    plugin::field(&CloudToScanParams::angle_increment, "angle_increment",
                  kCloudToScan.angle_increment, "angle between beams, rad"),
    plugin::field(&CloudToScanParams::scan_time, "scan_time", kCloudToScan.scan_time,
                  "time between scans, s, copied into the scan"),
    plugin::field(&CloudToScanParams::range_min, "range_min", kCloudToScan.range_min,
                  "shortest planar range kept, m"),
    plugin::field(&CloudToScanParams::range_max, "range_max", kCloudToScan.range_max,
                  "longest planar range kept, m"),
    plugin::field(&CloudToScanParams::use_inf, "use_inf", kCloudToScan.use_inf,
                  "beams without a point are +inf, else range_max + inf_epsilon"),
    plugin::field(&CloudToScanParams::inf_epsilon, "inf_epsilon", kCloudToScan.inf_epsilon,
                  "beyond range_max for beams without a point when use_inf is false, m")};

// PointCloudToLaserScanNode with target_frame empty or the cloud's own: each cloud as it comes.
class CloudToScanNode final : public SkippingNode {
 public:
  CloudToScanNode(graph::Context& context, const KernelConfig& config)
      : SkippingNode(context, config.node_name), params_(params_from(config)) {
    output_ = create_publisher<msgs::LaserScan>(config.topic("scan"), config.qos);
    cloud_sub_ = create_subscription<msgs::PointCloud2>(
        config.topic("cloud_in"), config.qos,
        [this](std::shared_ptr<const msgs::PointCloud2> cloud) { convert(*cloud); });
  }

  std::map<std::string, uint64_t> counters() const override {
    return {{"rejected_clouds", rejected_.count()}};
  }

 private:
  // Checked here, once, so that bad angles are one line when the graph is built.
  static CloudToScanParams params_from(const KernelConfig& config) {
    const CloudToScanParams p = kCloudToScanParameters.read(config.parameters);
    try {
      check(p);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("node '" + config.node_name + "': " + e.what());
    }
    return p;
  }

  void convert(const msgs::PointCloud2& cloud) {
    guarded([&] {
      plugin::trace_kernel_init(*this, kKernel, cloud.header.stamp.to_ns(), cloud);
      auto scan = std::make_shared<msgs::LaserScan>();
      point_cloud_to_laser_scan(cloud, params_, *scan);
      plugin::trace_kernel_fini(*this, kKernel, *scan);
      output_->publish(std::shared_ptr<const msgs::LaserScan>(std::move(scan)));
    });
  }

  static constexpr const char* kKernel = "pointcloud_to_laserscan/convert";
  CloudToScanParams params_;
  std::shared_ptr<graph::Publisher<msgs::LaserScan>> output_;
  std::shared_ptr<graph::GenericSubscription> cloud_sub_;
};

}  // namespace

void register_laser_scan_kernels(plugin::Registrar& registrar) {
  registrar.add_kernel(
      {.name = "depthimage_to_laserscan/convert",
       .description = "LaserScan of the rows about a depth image's principal point (per-column "
                      "minimum of the planar range), as depthimage_to_laserscan",
       .inputs = {{"depth", "sensor_msgs/msg/Image"},
                  {"depth_camera_info", "sensor_msgs/msg/CameraInfo"}},
       .outputs = {{"scan", "sensor_msgs/msg/LaserScan"}},
       .parameters = kDepthToScanParameters.declarations()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<DepthToScanNode>(context, config);
      });
  registrar.add_kernel(
      {.name = "pointcloud_to_laserscan/convert",
       .description = "LaserScan of the points of a cloud between two heights (per-beam minimum "
                      "of the planar range), as pointcloud_to_laserscan",
       .inputs = {{"cloud_in", "sensor_msgs/msg/PointCloud2"}},
       .outputs = {{"scan", "sensor_msgs/msg/LaserScan"}},
       .parameters = kCloudToScanParameters.declarations()},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<CloudToScanNode>(context, config);
      });
}

}  // namespace robotperf::perception
