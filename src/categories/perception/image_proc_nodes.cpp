// image_proc/rectify and image_proc/resize as graph nodes.
#include <stdexcept>

#include "camera_sync.hpp"
#include "category.hpp"
#include "device_node.hpp"
#include "output_pool.hpp"
#include "robotperf/perception/image_proc.hpp"
#include "skipping_node.hpp"

namespace robotperf::perception {
namespace {

using plugin::KernelConfig;

int interpolation_parameter(const KernelConfig& config) {
  const int64_t v = config.parameters.get_int("interpolation");
  if (v < cv::INTER_NEAREST || v > cv::INTER_LANCZOS4) {
    throw std::invalid_argument(
        "node '" + config.node_name +
        "': interpolation must be 0..4 (nearest, linear, cubic, area, lanczos4)");
  }
  return static_cast<int>(v);
}

// Subscribes `image` and `camera_info` and hands exact-time pairs to process(); a pair the kernel
// refuses (an uncalibrated camera, an image of another size than its CameraInfo) is skipped.
class CameraNode : public SkippingNode {
 public:
  std::map<std::string, uint64_t> counters() const override {
    return {{"rejected_sets", rejected_.count()}};
  }

 protected:
  CameraNode(graph::Context& context, const KernelConfig& config)
      : SkippingNode(context, config.node_name),
        sync_([this](const auto& img, const auto& info) { guarded([&] { process(img, info); }); }) {
    image_sub_ = create_subscription<msgs::Image>(
        config.topic("image"), config.qos,
        [this](std::shared_ptr<const msgs::Image> m) { sync_.add(std::move(m)); });
    info_sub_ = create_subscription<msgs::CameraInfo>(
        config.topic("camera_info"), config.qos,
        [this](std::shared_ptr<const msgs::CameraInfo> m) { sync_.add(std::move(m)); });
  }
  virtual void process(const CameraSync::ImagePtr& image, const CameraSync::InfoPtr& info) = 0;

 private:
  CameraSync sync_;
  std::shared_ptr<graph::GenericSubscription> image_sub_, info_sub_;
};

class RectifyNode final : public CameraNode, public ImageDeviceNode {
 public:
  RectifyNode(graph::Context& context, const KernelConfig& config,
              const RectifyImplementation& implementation)
      : CameraNode(context, config),
        ImageDeviceNode(implementation.device),
        rectifier_(interpolation_parameter(config), implementation),
        resident_(config.device_resident_outputs.contains("image_rect")) {
    output_ = create_publisher<msgs::Image>(config.topic("image_rect"), config.qos);
  }

 private:
  void process(const CameraSync::ImagePtr& image, const CameraSync::InfoPtr& info) override {
    plugin::trace_kernel_init(*this, kKernel, image->header.stamp.to_ns(), *image);
    const DeviceStageContext stages(*this, image->header.stamp.to_ns());
    std::shared_ptr<const msgs::Image> message;
    if (resident_) {
      // The next node takes the pixels on the device; a copy (no distortion) stays on the host.
      msgs::Image out;
      std::optional<ResidentPixels> pixels = rectifier_.rectify_on_device(*image, *info, out);
      message = pixels ? resident_image_message(std::move(out), std::move(*pixels))
                       : std::make_shared<const msgs::Image>(std::move(out));
    } else {
      std::shared_ptr<msgs::Image> out = pool_.acquire();
      rectifier_.rectify(*image, *info, *out);
      message = std::move(out);
    }
    plugin::trace_kernel_fini(*this, kKernel, *message);
    output_->publish(std::move(message));
  }

  static constexpr const char* kKernel = "image_proc/rectify";
  Rectifier rectifier_;
  bool resident_;  // image_rect's pixels stay on the device (a device-resident run)
  OutputPool<msgs::Image> pool_;
  std::shared_ptr<graph::Publisher<msgs::Image>> output_;
};

class ResizeNode final : public CameraNode, public ImageDeviceNode {
 public:
  ResizeNode(graph::Context& context, const KernelConfig& config,
             const ResizeImplementation& implementation)
      : CameraNode(context, config),
        ImageDeviceNode(implementation.device),
        resizer_(params_from(config), implementation) {
    image_out_ = create_publisher<msgs::Image>(config.topic("resize"), config.qos);
    info_out_ = create_publisher<msgs::CameraInfo>(config.topic("resize_info"), config.qos);
  }

 private:
  void process(const CameraSync::ImagePtr& image, const CameraSync::InfoPtr& info) override {
    std::shared_ptr<msgs::Image> out = pool_.acquire();
    auto out_info = std::make_shared<msgs::CameraInfo>();
    plugin::trace_kernel_init(*this, kKernel, image->header.stamp.to_ns(), *image);
    const DeviceStageContext stages(*this, image->header.stamp.to_ns());
    resizer_.resize(*image, *info, *out, *out_info, resident_pixels(image));
    plugin::trace_kernel_fini(*this, kKernel, *out);
    // CameraInfo first: a subscriber pairing on the image then finds its partner waiting.
    info_out_->publish(std::shared_ptr<const msgs::CameraInfo>(std::move(out_info)));
    image_out_->publish(std::shared_ptr<const msgs::Image>(std::move(out)));
  }

  static ResizeParams params_from(const KernelConfig& config) {
    const auto& p = config.parameters;
    ResizeParams params;
    params.use_scale = p.get_bool("use_scale");
    params.scale_height = p.get_double("scale_height");
    params.scale_width = p.get_double("scale_width");
    params.height = p.get_int32("height");
    params.width = p.get_int32("width");
    params.interpolation = interpolation_parameter(config);
    return params;
  }

  static constexpr const char* kKernel = "image_proc/resize";
  Resizer resizer_;
  OutputPool<msgs::Image> pool_;
  std::shared_ptr<graph::Publisher<msgs::Image>> image_out_;
  std::shared_ptr<graph::Publisher<msgs::CameraInfo>> info_out_;
};

plugin::ParameterInfo interpolation_declaration() {
  return plugin::int_parameter("interpolation", cv::INTER_LINEAR,
                               "cv::InterpolationFlags: 0 nearest, 1 linear, 2 cubic, 3 area, "
                               "4 lanczos4");
}

// image_transport's camera subscriber: the image (which the node may take on its device, in a
// device-resident run) and its CameraInfo.
std::vector<plugin::PortInfo> camera_inputs(bool image_on_device) {
  return {{"image", "sensor_msgs/msg/Image", image_on_device},
          {"camera_info", "sensor_msgs/msg/CameraInfo"}};
}

}  // namespace

void register_image_proc_kernels(plugin::Registrar& registrar) {
  register_implementations(
      registrar,
      {.name = "image_proc/rectify",
       .description = "undistort and rectify an image with its CameraInfo (cached map, cv::remap), "
                      "as image_proc",
       .inputs = camera_inputs(false),
       .outputs = {{"image_rect", "sensor_msgs/msg/Image", true}},
       .parameters = {interpolation_declaration()}},
      rectify_implementations(),
      [](graph::Context& context, const KernelConfig& config, const RectifyImplementation& i) {
        return std::make_shared<RectifyNode>(context, config, i);
      });
  const ResizeParams defaults;
  register_implementations(
      registrar,
      {.name = "image_proc/resize",
       .description = "resize an image and scale its CameraInfo (K, P, ROI), as image_proc",
       .inputs = camera_inputs(true),
       .outputs = {{"resize", "sensor_msgs/msg/Image"},
                   {"resize_info", "sensor_msgs/msg/CameraInfo"}},
       .parameters =
           {plugin::bool_parameter("use_scale", defaults.use_scale,
                                   "true: scale by scale_width x scale_height; false: resize to "
                                   "width x height"),
            plugin::double_parameter("scale_height", defaults.scale_height, "height factor"),
            plugin::double_parameter("scale_width", defaults.scale_width, "width factor"),
            plugin::int_parameter("height", defaults.height,
                                  "target height without use_scale; -1 keeps the input's"),
            plugin::int_parameter("width", defaults.width,
                                  "target width without use_scale; -1 keeps the input's"),
            interpolation_declaration()}},
      resize_implementations(),
      [](graph::Context& context, const KernelConfig& config, const ResizeImplementation& i) {
        return std::make_shared<ResizeNode>(context, config, i);
      });
}

}  // namespace robotperf::perception
