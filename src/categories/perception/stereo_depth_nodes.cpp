// stereo_image_proc/disparity and depth_image_proc/point_cloud_xyzrgb as graph nodes.
#include <cmath>
#include <stdexcept>

#include "category.hpp"
#include "device_node.hpp"
#include "output_pool.hpp"
#include "robotperf/perception/depth_image_proc.hpp"
#include "robotperf/perception/stereo_image_proc.hpp"
#include "robotperf/plugin/synced_inputs.hpp"
#include "skipping_node.hpp"

namespace robotperf::perception {
namespace {

using plugin::KernelConfig;
using plugin::SyncOptions;
using plugin::SyncPolicy;

SyncOptions sync_options(const KernelConfig& config, bool approximate) {
  SyncOptions o;
  o.policy = approximate ? SyncPolicy::kApproximate : SyncPolicy::kExact;
  const int64_t queue = config.parameters.get_int("queue_size");
  if (queue < 1)
    throw std::invalid_argument("node '" + config.node_name + "': queue_size must be >= 1");
  o.queue_size = static_cast<std::size_t>(queue);
  return o;
}

class DisparityNode final : public SkippingNode, public ImageDeviceNode {
 public:
  enum Input { kLeftImage, kLeftInfo, kRightImage, kRightInfo };

  DisparityNode(graph::Context& context, const KernelConfig& config,
                const DisparityImplementation& implementation)
      : SkippingNode(context, config.node_name),
        ImageDeviceNode(implementation.device),
        processor_(params_from(config), implementation),
        inputs_({"left_image", "left_camera_info", "right_image", "right_camera_info"},
                sync_options(config, config.parameters.get_bool("approximate_sync")),
                [this](const Inputs::Set& set) { process(set); }) {
    output_ = create_publisher<msgs::DisparityImage>(config.topic("disparity"), config.qos);
    inputs_.subscribe<msgs::Image>(*this, config, kLeftImage);
    inputs_.subscribe<msgs::CameraInfo>(*this, config, kLeftInfo);
    inputs_.subscribe<msgs::Image>(*this, config, kRightImage);
    inputs_.subscribe<msgs::CameraInfo>(*this, config, kRightInfo);
  }

  std::map<std::string, uint64_t> counters() const override {
    std::map<std::string, uint64_t> out = inputs_.counters();
    out["rejected_sets"] = rejected_.count();
    return out;
  }

 private:
  static StereoParams params_from(const KernelConfig& c) {
    StereoParams p;
    const int algorithm = c.parameters.get_int32("stereo_algorithm");
    if (algorithm != 0 && algorithm != 1) {
      throw std::invalid_argument("node '" + c.node_name +
                                  "': stereo_algorithm must be 0 (StereoBM) or 1 (StereoSGBM)");
    }
    p.algorithm = static_cast<StereoAlgorithm>(algorithm);
    p.prefilter_size = c.parameters.get_int32("prefilter_size");
    p.prefilter_cap = c.parameters.get_int32("prefilter_cap");
    p.correlation_window_size = c.parameters.get_int32("correlation_window_size");
    p.min_disparity = c.parameters.get_int32("min_disparity");
    p.disparity_range = c.parameters.get_int32("disparity_range");
    p.texture_threshold = c.parameters.get_int32("texture_threshold");
    p.speckle_size = c.parameters.get_int32("speckle_size");
    p.speckle_range = c.parameters.get_int32("speckle_range");
    p.uniqueness_ratio = c.parameters.get_int32("uniqueness_ratio");
    p.p1 = c.parameters.get_int32("P1");
    p.p2 = c.parameters.get_int32("P2");
    p.disp12_max_diff = c.parameters.get_int32("disp12_max_diff");
    p.sgbm_mode = c.parameters.get_int32("sgbm_mode");
    try {
      validate(p);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("node '" + c.node_name + "': " + e.what());
    }
    return p;
  }

  using Inputs = plugin::SyncedInputs<4>;

  void process(const Inputs::Set& set) {
    guarded([&] {
      std::shared_ptr<msgs::DisparityImage> out = pool_.acquire();
      const auto& left = Inputs::message<msgs::Image>(set, kLeftImage);
      const auto& right = Inputs::message<msgs::Image>(set, kRightImage);
      plugin::trace_kernel_init(*this, kKernel, left.header.stamp.to_ns(), left, right);
      const DeviceStageContext stages(*this, left.header.stamp.to_ns());
      processor_.compute(left, right, Inputs::message<msgs::CameraInfo>(set, kLeftInfo),
                         Inputs::message<msgs::CameraInfo>(set, kRightInfo), *out);
      plugin::trace_kernel_fini(*this, kKernel, *out);
      output_->publish(std::shared_ptr<const msgs::DisparityImage>(std::move(out)));
    });
  }

  static constexpr const char* kKernel = "stereo_image_proc/disparity";
  DisparityProcessor processor_;
  OutputPool<msgs::DisparityImage> pool_;
  Inputs inputs_;
  std::shared_ptr<graph::Publisher<msgs::DisparityImage>> output_;
};

class PointCloudXyzrgbNode final : public SkippingNode, public ImageDeviceNode {
 public:
  enum Input { kDepth, kImage, kInfo };

  PointCloudXyzrgbNode(graph::Context& context, const KernelConfig& config,
                       const PointCloudImplementation& implementation)
      : SkippingNode(context, config.node_name),
        ImageDeviceNode(implementation.device),
        processor_(implementation),
        inputs_({"depth", "image", "camera_info"},
                sync_options(config, !config.parameters.get_bool("exact_sync")),
                [this](const Inputs::Set& set) { process(set); }) {
    params_.range_max = config.parameters.get_double("range_max");
    if (!(params_.range_max >= 0.0) || !std::isfinite(params_.range_max)) {
      throw std::invalid_argument("node '" + config.node_name + "': range_max must be >= 0");
    }
    output_ = create_publisher<msgs::PointCloud2>(config.topic("points"), config.qos);
    inputs_.subscribe<msgs::Image>(*this, config, kDepth);
    inputs_.subscribe<msgs::Image>(*this, config, kImage);
    inputs_.subscribe<msgs::CameraInfo>(*this, config, kInfo);
  }

  std::map<std::string, uint64_t> counters() const override {
    std::map<std::string, uint64_t> out = inputs_.counters();
    out["rejected_sets"] = rejected_.count();
    return out;
  }

 private:
  using Inputs = plugin::SyncedInputs<3>;

  void process(const Inputs::Set& set) {
    guarded([&] {
      std::shared_ptr<msgs::PointCloud2> cloud = pool_.acquire();
      const auto& depth = Inputs::message<msgs::Image>(set, kDepth);
      const auto& image = Inputs::message<msgs::Image>(set, kImage);
      plugin::trace_kernel_init(*this, kKernel, depth.header.stamp.to_ns(), depth, image);
      const DeviceStageContext stages(*this, depth.header.stamp.to_ns());
      processor_.compute(depth, image, Inputs::message<msgs::CameraInfo>(set, kInfo), params_,
                         *cloud);
      plugin::trace_kernel_fini(*this, kKernel, *cloud);
      output_->publish(std::shared_ptr<const msgs::PointCloud2>(std::move(cloud)));
    });
  }

  static constexpr const char* kKernel = "depth_image_proc/point_cloud_xyzrgb";
  PointCloudXyzrgbParams params_;
  PointCloudXyzrgbProcessor processor_;
  OutputPool<msgs::PointCloud2> pool_;
  Inputs inputs_;
  std::shared_ptr<graph::Publisher<msgs::PointCloud2>> output_;
};

plugin::ParameterInfo queue_size_declaration() {
  return plugin::int_parameter("queue_size", 5,
                               "frames (exact sync) or messages per input (approximate sync) "
                               "waiting to be paired");
}

}  // namespace

void register_stereo_depth_kernels(plugin::Registrar& registrar) {
  const StereoParams d;
  using plugin::int_parameter;
  register_implementations(
      registrar,
      {.name = "stereo_image_proc/disparity",
       .description = "disparity of a rectified stereo pair (StereoBM, or StereoSGBM), as "
                      "stereo_image_proc",
       .inputs = {{"left_image", "sensor_msgs/msg/Image"},
                  {"left_camera_info", "sensor_msgs/msg/CameraInfo"},
                  {"right_image", "sensor_msgs/msg/Image"},
                  {"right_camera_info", "sensor_msgs/msg/CameraInfo"}},
       .outputs = {{"disparity", "stereo_msgs/msg/DisparityImage"}},
       .parameters =
           {int_parameter("stereo_algorithm", static_cast<int>(d.algorithm),
                          "0 StereoBM, 1 StereoSGBM"),
            int_parameter("prefilter_size", d.prefilter_size, "StereoBM: odd, 5..255"),
            int_parameter("prefilter_cap", d.prefilter_cap, "1..63"),
            int_parameter("correlation_window_size", d.correlation_window_size,
                          "odd; StereoBM 5..255, StereoSGBM 1..255"),
            int_parameter("min_disparity", d.min_disparity, "smallest disparity searched, px"),
            int_parameter("disparity_range", d.disparity_range,
                          "disparities searched, a positive multiple of 16"),
            int_parameter("texture_threshold", d.texture_threshold, "StereoBM only"),
            int_parameter("speckle_size", d.speckle_size, "largest speckle filtered out, px"),
            int_parameter("speckle_range", d.speckle_range, "disparity spread within a speckle"),
            int_parameter("uniqueness_ratio", d.uniqueness_ratio, "margin of the best match, %"),
            int_parameter("P1", d.p1, "StereoSGBM smoothness penalty, small changes"),
            int_parameter("P2", d.p2, "StereoSGBM smoothness penalty, large changes"),
            int_parameter("disp12_max_diff", d.disp12_max_diff,
                          "StereoSGBM left-right check tolerance"),
            int_parameter("sgbm_mode", d.sgbm_mode,
                          "cv::StereoSGBM mode: 0 SGBM, 1 HH, 2 SGBM_3WAY, 3 HH4"),
            plugin::bool_parameter("approximate_sync", false,
                                   "pair inputs by nearby stamps instead of equal ones"),
            queue_size_declaration()}},
      disparity_implementations(),
      [](graph::Context& context, const KernelConfig& config, const DisparityImplementation& i) {
        return std::make_shared<DisparityNode>(context, config, i);
      });
  register_implementations(
      registrar,
      {.name = "depth_image_proc/point_cloud_xyzrgb",
       .description = "organised xyz + rgb point cloud from registered depth and colour, as "
                      "depth_image_proc",
       .inputs = {{"depth", "sensor_msgs/msg/Image"},
                  {"image", "sensor_msgs/msg/Image"},
                  {"camera_info", "sensor_msgs/msg/CameraInfo"}},
       .outputs = {{"points", "sensor_msgs/msg/PointCloud2"}},
       .parameters = {plugin::double_parameter("range_max", PointCloudXyzrgbParams{}.range_max,
                                               "depth given to invalid pixels, m; 0 makes them "
                                               "NaN points"),
                      plugin::bool_parameter("exact_sync", false,
                                             "pair inputs by equal stamps instead of nearby ones"),
                      queue_size_declaration()}},
      point_cloud_implementations(),
      [](graph::Context& context, const KernelConfig& config, const PointCloudImplementation& i) {
        return std::make_shared<PointCloudXyzrgbNode>(context, config, i);
      });
}

}  // namespace robotperf::perception
