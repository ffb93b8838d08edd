// image_proc/rectify and image_proc/resize as graph nodes.
#include <stdexcept>

#include "builtin_kernels.hpp"
#include "camera_sync.hpp"
#include "robotperf/kernels/image_proc.hpp"
#include "robotperf/tracing/tracepoints.hpp"

namespace robotperf::kernels {
namespace {

int interpolation_parameter(const KernelConfig& config) {
  const int64_t v = config.parameters.get_int("interpolation", cv::INTER_LINEAR);
  if (v < cv::INTER_NEAREST || v > cv::INTER_LANCZOS4) {
    throw std::invalid_argument(
        "node '" + config.node_name +
        "': interpolation must be 0..4 (nearest, linear, cubic, area, lanczos4)");
  }
  return static_cast<int>(v);
}

// Subscribes `image` and `camera_info` and hands exact-time pairs to process().
class CameraNode : public graph::Node {
 protected:
  CameraNode(graph::Context& context, const KernelConfig& config)
      : Node(context, config.node_name),
        sync_([this](const auto& img, const auto& info) { process(img, info); }) {
    image_sub_ = create_subscription<msgs::Image>(
        config.topic("image"), config.qos,
        [this](std::shared_ptr<const msgs::Image> m) { sync_.add(std::move(m)); });
    info_sub_ = create_subscription<msgs::CameraInfo>(
        config.topic("camera_info"), config.qos,
        [this](std::shared_ptr<const msgs::CameraInfo> m) { sync_.add(std::move(m)); });
  }
  virtual void process(const CameraSync::ImagePtr& image, const CameraSync::InfoPtr& info) = 0;

  // robotperf:kernel_init/fini around a kernel's computation on `image`; the
  // sizes are CDR sizes from a sizing pass, computed only while traced.
  void trace_kernel_init(const char* kernel, const msgs::Image& image) const {
    if (lttng_ust_tracepoint_enabled(robotperf, kernel_init)) {
      lttng_ust_do_tracepoint(robotperf, kernel_init, name().c_str(), kernel, stamp_of(image),
                              msgs::type_support<msgs::Image>().serialized_size(&image));
    }
  }
  void trace_kernel_fini(const char* kernel, const msgs::Image& output) const {
    lttng_ust_tracepoint(robotperf, kernel_fini, name().c_str(), kernel, stamp_of(output),
                         msgs::type_support<msgs::Image>().serialized_size(&output));
  }
  static int64_t stamp_of(const msgs::Image& m) {
    return int64_t{m.header.stamp.sec} * 1'000'000'000 + m.header.stamp.nanosec;
  }

 private:
  CameraSync sync_;
  std::shared_ptr<graph::GenericSubscription> image_sub_, info_sub_;
};

class RectifyNode final : public CameraNode {
 public:
  RectifyNode(graph::Context& context, const KernelConfig& config)
      : CameraNode(context, config), rectifier_(interpolation_parameter(config)) {
    output_ = create_publisher<msgs::Image>(config.topic("image_rect"), config.qos);
  }

 private:
  void process(const CameraSync::ImagePtr& image, const CameraSync::InfoPtr& info) override {
    auto out = std::make_shared<msgs::Image>();
    trace_kernel_init(kKernel, *image);
    rectifier_.rectify(*image, *info, *out);
    trace_kernel_fini(kKernel, *out);
    output_->publish(std::shared_ptr<const msgs::Image>(std::move(out)));
  }

  static constexpr const char* kKernel = "image_proc/rectify";
  Rectifier rectifier_;
  std::shared_ptr<graph::Publisher<msgs::Image>> output_;
};

class ResizeNode final : public CameraNode {
 public:
  ResizeNode(graph::Context& context, const KernelConfig& config) : CameraNode(context, config) {
    const auto& p = config.parameters;
    params_.use_scale = p.get_bool("use_scale", true);
    params_.scale_height = p.get_double("scale_height", 1.0);
    params_.scale_width = p.get_double("scale_width", 1.0);
    params_.height = static_cast<int>(p.get_int("height", -1));
    params_.width = static_cast<int>(p.get_int("width", -1));
    params_.interpolation = interpolation_parameter(config);
    image_out_ = create_publisher<msgs::Image>(config.topic("resize"), config.qos);
    info_out_ = create_publisher<msgs::CameraInfo>(config.topic("resize_info"), config.qos);
  }

 private:
  void process(const CameraSync::ImagePtr& image, const CameraSync::InfoPtr& info) override {
    auto out = std::make_shared<msgs::Image>();
    auto out_info = std::make_shared<msgs::CameraInfo>();
    trace_kernel_init(kKernel, *image);
    resize(*image, *info, params_, *out, *out_info);
    trace_kernel_fini(kKernel, *out);
    // CameraInfo first: a subscriber pairing on the image then finds its partner waiting.
    info_out_->publish(std::shared_ptr<const msgs::CameraInfo>(std::move(out_info)));
    image_out_->publish(std::shared_ptr<const msgs::Image>(std::move(out)));
  }

  static constexpr const char* kKernel = "image_proc/resize";
  ResizeParams params_;
  std::shared_ptr<graph::Publisher<msgs::Image>> image_out_;
  std::shared_ptr<graph::Publisher<msgs::CameraInfo>> info_out_;
};

}  // namespace

std::shared_ptr<graph::Node> make_rectify_node(graph::Context& context,
                                               const KernelConfig& config) {
  return std::make_shared<RectifyNode>(context, config);
}

std::shared_ptr<graph::Node> make_resize_node(graph::Context& context, const KernelConfig& config) {
  return std::make_shared<ResizeNode>(context, config);
}

}  // namespace robotperf::kernels
