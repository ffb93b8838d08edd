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

// The interpolation both kernels take, in their settings struct S.
template <class S>
plugin::ParameterField<S> interpolation_field(int S::*member) {
  return plugin::field(member, "interpolation", cv::INTER_LINEAR,
                       "cv::InterpolationFlags: 0 nearest, 1 linear, 2 cubic, 3 area, 4 lanczos4");
}

int checked_interpolation(const KernelConfig& config, int v) {
  if (v < cv::INTER_NEAREST || v > cv::INTER_LANCZOS4) {
    throw std::invalid_argument(
        "node '" + config.node_name +
        "': interpolation must be 0..4 (nearest, linear, cubic, area, lanczos4)");
  }
  return v;
}

struct RectifySettings {
  int interpolation = 0;
};

const plugin::ParameterStruct<RectifySettings> kRectifyParameters{
    interpolation_field(&RectifySettings::interpolation)};

const ResizeParams kResize;
const plugin::ParameterStruct<ResizeParams> kResizeParameters{
    plugin::field(&ResizeParams::use_scale, "use_scale", kResize.use_scale,
                  "true: scale by scale_width x scale_height; false: resize to width x height"),
    plugin::field(&ResizeParams::scale_height, "scale_height", kResize.scale_height,
                  "height factor"),
    plugin::field(&ResizeParams::scale_width, "scale_width", kResize.scale_width, "width factor"),
    plugin::field(&ResizeParams::height, "height", kResize.height,
                  "target height without use_scale; -1 keeps the input's"),
    plugin::field(&ResizeParams::width, "width", kResize.width,
                  "target width without use_scale; -1 keeps the input's"),
    interpolation_field(&ResizeParams::interpolation)};

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
        rectifier_(
            checked_interpolation(config, kRectifyParameters.read(config.parameters).interpolation),
            implementation),
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
    ResizeParams params = kResizeParameters.read(config.parameters);
    checked_interpolation(config, params.interpolation);
    return params;
  }

  static constexpr const char* kKernel = "image_proc/resize";
  Resizer resizer_;
  OutputPool<msgs::Image> pool_;
  std::shared_ptr<graph::Publisher<msgs::Image>> image_out_;
  std::shared_ptr<graph::Publisher<msgs::CameraInfo>> info_out_;
};

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
       .parameters = kRectifyParameters.declarations()},
      rectify_implementations(),
      [](graph::Context& context, const KernelConfig& config, const RectifyImplementation& i) {
        return std::make_shared<RectifyNode>(context, config, i);
      });
  register_implementations(
      registrar,
      {.name = "image_proc/resize",
       .description = "resize an image and scale its CameraInfo (K, P, ROI), as image_proc",
       .inputs = camera_inputs(true),
       .outputs = {{"resize", "sensor_msgs/msg/Image"},
                   {"resize_info", "sensor_msgs/msg/CameraInfo"}},
       .parameters = kResizeParameters.declarations()},
      resize_implementations(),
      [](graph::Context& context, const KernelConfig& config, const ResizeImplementation& i) {
        return std::make_shared<ResizeNode>(context, config, i);
      });
}

}  // namespace robotperf::perception
