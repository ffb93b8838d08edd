// stereo_image_proc/disparity, stereo_image_proc/point_cloud and
// depth_image_proc/point_cloud_xyzrgb as graph nodes.
#include <cmath>
#include <stdexcept>

#include "category.hpp"
#include "device_node.hpp"
#include "output_pool.hpp"
#include "robotperf/perception/depth_image_proc.hpp"
#include "robotperf/perception/stereo_image_proc.hpp"
#include "robotperf/perception/stereo_point_cloud.hpp"
#include "robotperf/plugin/synced_inputs.hpp"
#include "skipping_node.hpp"

namespace robotperf::perception {
namespace {

using plugin::KernelConfig;
using plugin::SyncOptions;
using plugin::SyncPolicy;

// The queue both kernels take, in their settings struct S.
template <class S>
plugin::ParameterField<S> queue_size_field(int64_t S::*member) {
  return plugin::field(member, "queue_size", 5,
                       "frames (exact sync) or messages per input (approximate sync) waiting to "
                       "be paired");
}

SyncOptions sync_options(const KernelConfig& config, bool approximate, int64_t queue) {
  SyncOptions o;
  o.policy = approximate ? SyncPolicy::kApproximate : SyncPolicy::kExact;
  if (queue < 1)
    throw std::invalid_argument("node '" + config.node_name + "': queue_size must be >= 1");
  o.queue_size = static_cast<std::size_t>(queue);
  return o;
}

struct DisparitySettings {
  int stereo_algorithm = 0;  // StereoParams' algorithm, as its number
  StereoParams stereo;       // the rest
  bool approximate_sync = false;
  int64_t queue_size = 0;
};

const StereoParams kStereo;
const plugin::ParameterStruct<StereoParams> kStereoParameters{
    plugin::field(&StereoParams::prefilter_size, "prefilter_size", kStereo.prefilter_size,
                  "StereoBM: odd, 5..255"),
    plugin::field(&StereoParams::prefilter_cap, "prefilter_cap", kStereo.prefilter_cap, "1..63"),
    plugin::field(&StereoParams::correlation_window_size, "correlation_window_size",
                  kStereo.correlation_window_size, "odd; StereoBM 5..255, StereoSGBM 1..255"),
    plugin::field(&StereoParams::min_disparity, "min_disparity", kStereo.min_disparity,
                  "smallest disparity searched, px"),
    plugin::field(&StereoParams::disparity_range, "disparity_range", kStereo.disparity_range,
                  "disparities searched, a positive multiple of 16"),
    plugin::field(&StereoParams::texture_threshold, "texture_threshold", kStereo.texture_threshold,
                  "StereoBM only"),
    plugin::field(&StereoParams::speckle_size, "speckle_size", kStereo.speckle_size,
                  "largest speckle filtered out, px"),
    plugin::field(&StereoParams::speckle_range, "speckle_range", kStereo.speckle_range,
                  "disparity spread within a speckle"),
    plugin::field(&StereoParams::uniqueness_ratio, "uniqueness_ratio", kStereo.uniqueness_ratio,
                  "margin of the best match, %"),
    plugin::field(&StereoParams::p1, "P1", kStereo.p1,
                  "StereoSGBM smoothness penalty, small changes"),
    plugin::field(&StereoParams::p2, "P2", kStereo.p2,
                  "StereoSGBM smoothness penalty, large changes"),
    plugin::field(&StereoParams::disp12_max_diff, "disp12_max_diff", kStereo.disp12_max_diff,
                  "StereoSGBM left-right check tolerance"),
    plugin::field(&StereoParams::sgbm_mode, "sgbm_mode", kStereo.sgbm_mode,
                  "cv::StereoSGBM mode: 0 SGBM, 1 HH, 2 SGBM_3WAY, 3 HH4")};

const plugin::ParameterStruct<DisparitySettings> kDisparityParameters{
    plugin::field(&DisparitySettings::stereo_algorithm, "stereo_algorithm",
                  static_cast<int>(kStereo.algorithm), "0 StereoBM, 1 StereoSGBM"),
    plugin::nested(&DisparitySettings::stereo, kStereoParameters),
    plugin::field(&DisparitySettings::approximate_sync, "approximate_sync", false,
                  "pair inputs by nearby stamps instead of equal ones"),
    queue_size_field(&DisparitySettings::queue_size)};

struct PointCloudSettings {
  double range_max = 0;
  bool exact_sync = false;
  int64_t queue_size = 0;
};

const plugin::ParameterStruct<PointCloudSettings> kPointCloudParameters{
    plugin::field(&PointCloudSettings::range_max, "range_max", PointCloudXyzrgbParams{}.range_max,
                  "depth given to invalid pixels, m; 0 makes them NaN points"),
    plugin::field(&PointCloudSettings::exact_sync, "exact_sync", false,
                  "pair inputs by equal stamps instead of nearby ones"),
    queue_size_field(&PointCloudSettings::queue_size)};

struct StereoPointCloudSettings {
  StereoPointCloudParams cloud;
  bool approximate_sync = false;
  int64_t queue_size = 0;
};

const StereoPointCloudParams kStereoPointCloud;
const plugin::ParameterStruct<StereoPointCloudSettings> kStereoPointCloudParameters{
    plugin::field(&StereoPointCloudSettings::approximate_sync, "approximate_sync", false,
                  "pair inputs by nearby stamps instead of equal ones"),
    queue_size_field(&StereoPointCloudSettings::queue_size),
    plugin::nested(
        &StereoPointCloudSettings::cloud,
        plugin::ParameterStruct<StereoPointCloudParams>{
            plugin::field(&StereoPointCloudParams::use_color, "use_color",
                          kStereoPointCloud.use_color, "an rgb field from the left image"),
            plugin::field(&StereoPointCloudParams::avoid_point_cloud_padding,
                          "avoid_point_cloud_padding", kStereoPointCloud.avoid_point_cloud_padding,
                          "fields back to back, without alignment padding")})};

class DisparityNode final : public SkippingNode, public ImageDeviceNode {
 public:
  enum Input { kLeftImage, kLeftInfo, kRightImage, kRightInfo };

  DisparityNode(graph::Context& context, const KernelConfig& config,
                const DisparityImplementation& implementation)
      : SkippingNode(context, config.node_name),
        ImageDeviceNode(implementation.device),
        processor_(params_from(config), implementation),
        inputs_({"left_image", "left_camera_info", "right_image", "right_camera_info"},
                sync_from(config), [this](const Inputs::Set& set) { process(set); }) {
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
    const DisparitySettings s = kDisparityParameters.read(c.parameters);
    if (s.stereo_algorithm != 0 && s.stereo_algorithm != 1) {
      throw std::invalid_argument("node '" + c.node_name +
                                  "': stereo_algorithm must be 0 (StereoBM) or 1 (StereoSGBM)");
    }
    StereoParams p = s.stereo;
    p.algorithm = static_cast<StereoAlgorithm>(s.stereo_algorithm);
    try {
      validate(p);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("node '" + c.node_name + "': " + e.what());
    }
    return p;
  }

  static SyncOptions sync_from(const KernelConfig& c) {
    const DisparitySettings s = kDisparityParameters.read(c.parameters);
    return sync_options(c, s.approximate_sync, s.queue_size);
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

// stereo_image_proc's PointCloudNode: the left image, both CameraInfos and the disparity, paired.
class StereoPointCloudNode final : public SkippingNode, public ImageDeviceNode {
 public:
  enum Input { kLeftImage, kLeftInfo, kRightInfo, kDisparity };

  StereoPointCloudNode(graph::Context& context, const KernelConfig& config,
                       const StereoPointCloudImplementation& implementation)
      : SkippingNode(context, config.node_name),
        ImageDeviceNode(implementation.device),
        settings_(kStereoPointCloudParameters.read(config.parameters)),
        processor_(implementation),
        inputs_({"left_image", "left_camera_info", "right_camera_info", "disparity"},
                sync_options(config, settings_.approximate_sync, settings_.queue_size),
                [this](const Inputs::Set& set) { process(set); }) {
    output_ = create_publisher<msgs::PointCloud2>(config.topic("points2"), config.qos);
    inputs_.subscribe<msgs::Image>(*this, config, kLeftImage);
    inputs_.subscribe<msgs::CameraInfo>(*this, config, kLeftInfo);
    inputs_.subscribe<msgs::CameraInfo>(*this, config, kRightInfo);
    inputs_.subscribe<msgs::DisparityImage>(*this, config, kDisparity);
  }

  std::map<std::string, uint64_t> counters() const override {
    std::map<std::string, uint64_t> out = inputs_.counters();
    out["rejected_sets"] = rejected_.count();
    return out;
  }

 private:
  using Inputs = plugin::SyncedInputs<4>;

  void process(const Inputs::Set& set) {
    guarded([&] {
      std::shared_ptr<msgs::PointCloud2> cloud = pool_.acquire();
      const auto& disparity = Inputs::message<msgs::DisparityImage>(set, kDisparity);
      const auto& left = Inputs::message<msgs::Image>(set, kLeftImage);
      plugin::trace_kernel_init(*this, kKernel, disparity.header.stamp.to_ns(), disparity, left);
      const DeviceStageContext stages(*this, disparity.header.stamp.to_ns());
      processor_.compute(left, Inputs::message<msgs::CameraInfo>(set, kLeftInfo),
                         Inputs::message<msgs::CameraInfo>(set, kRightInfo), disparity,
                         settings_.cloud, *cloud);
      plugin::trace_kernel_fini(*this, kKernel, *cloud);
      output_->publish(std::shared_ptr<const msgs::PointCloud2>(std::move(cloud)));
    });
  }

  static constexpr const char* kKernel = "stereo_image_proc/point_cloud";
  StereoPointCloudSettings settings_;
  StereoPointCloudProcessor processor_;
  OutputPool<msgs::PointCloud2> pool_;
  Inputs inputs_;
  std::shared_ptr<graph::Publisher<msgs::PointCloud2>> output_;
};

class PointCloudXyzrgbNode final : public SkippingNode, public ImageDeviceNode {
 public:
  enum Input { kDepth, kImage, kInfo };

  PointCloudXyzrgbNode(graph::Context& context, const KernelConfig& config,
                       const PointCloudImplementation& implementation)
      : SkippingNode(context, config.node_name),
        ImageDeviceNode(implementation.device),
        processor_(implementation),
        inputs_({"depth", "image", "camera_info"}, sync_from(config),
                [this](const Inputs::Set& set) { process(set); }) {
    params_.range_max = kPointCloudParameters.read(config.parameters).range_max;
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

  static SyncOptions sync_from(const KernelConfig& c) {
    const PointCloudSettings s = kPointCloudParameters.read(c.parameters);
    return sync_options(c, !s.exact_sync, s.queue_size);
  }

  static constexpr const char* kKernel = "depth_image_proc/point_cloud_xyzrgb";
  PointCloudXyzrgbParams params_;
  PointCloudXyzrgbProcessor processor_;
  OutputPool<msgs::PointCloud2> pool_;
  Inputs inputs_;
  std::shared_ptr<graph::Publisher<msgs::PointCloud2>> output_;
};

}  // namespace

void register_stereo_depth_kernels(plugin::Registrar& registrar) {
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
       .parameters = kDisparityParameters.declarations()},
      disparity_implementations(),
      [](graph::Context& context, const KernelConfig& config, const DisparityImplementation& i) {
        return std::make_shared<DisparityNode>(context, config, i);
      });
  register_implementations(
      registrar,
      {.name = "stereo_image_proc/point_cloud",
       .description = "organised xyz (+ rgb) point cloud from a disparity image, its left image "
                      "and the pair's CameraInfos, as stereo_image_proc",
       .inputs = {{"left_image", "sensor_msgs/msg/Image"},
                  {"left_camera_info", "sensor_msgs/msg/CameraInfo"},
                  {"right_camera_info", "sensor_msgs/msg/CameraInfo"},
                  {"disparity", "stereo_msgs/msg/DisparityImage"}},
       .outputs = {{"points2", "sensor_msgs/msg/PointCloud2"}},
       .parameters = kStereoPointCloudParameters.declarations()},
      stereo_point_cloud_implementations(),
      [](graph::Context& context, const KernelConfig& config,
         const StereoPointCloudImplementation& i) {
        return std::make_shared<StereoPointCloudNode>(context, config, i);
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
       .parameters = kPointCloudParameters.declarations()},
      point_cloud_implementations(),
      [](graph::Context& context, const KernelConfig& config, const PointCloudImplementation& i) {
        return std::make_shared<PointCloudXyzrgbNode>(context, config, i);
      });
}

}  // namespace robotperf::perception
