// The localization kernels as graph nodes.
#include <iostream>
#include <stdexcept>

#include "category.hpp"
#include "robotperf/localization/apriltag_detector.hpp"
#include "robotperf/msgs/apriltag_msgs.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/sensor_msgs.hpp"

namespace robotperf::localization {
namespace {

using plugin::KernelConfig;
using plugin::MessageSync;

// Inputs paired by exact stamps (as the ROS nodes' message_filters do); inputs the kernel rejects
// are skipped and counted, as the ROS nodes log and skip them: the frame shows as lost at the
// Monitor.
template <std::size_t N>
class SyncedNode : public graph::Node, public plugin::NodeCounters {
 public:
  std::map<std::string, uint64_t> counters() const override {
    std::map<std::string, uint64_t> out{{"sets_processed", sync_.emitted()},
                                        {"rejected_sets", rejected_}};
    for (std::size_t i = 0; i < N; ++i) out["unpaired_" + port_names_[i]] = sync_.dropped()[i];
    return out;
  }

 protected:
  SyncedNode(graph::Context& context, const KernelConfig& config,
             std::array<std::string, N> port_names)
      : Node(context, config.node_name),
        port_names_(std::move(port_names)),
        sync_(plugin::SyncOptions{}, [this](const auto& set) { guarded(set); }) {}

  template <class T>
  void subscribe(const KernelConfig& config, std::size_t input) {
    subscriptions_.push_back(create_subscription<T>(config.topic(port_names_[input]), config.qos,
                                                    [this, input](std::shared_ptr<const T> m) {
                                                      const int64_t stamp = m->header.stamp.to_ns();
                                                      sync_.add(input, std::move(m), stamp);
                                                    }));
  }

  virtual void process(const typename MessageSync<N>::Set& set) = 0;

 private:
  void guarded(const typename MessageSync<N>::Set& set) {
    try {
      process(set);
    } catch (const std::invalid_argument& e) {
      if (rejected_++ == 0)
        std::cerr << "robotperf node " << name() << ": skipping input: " << e.what() << "\n";
    }
  }

  std::array<std::string, N> port_names_;
  MessageSync<N> sync_;
  uint64_t rejected_ = 0;
  std::vector<std::shared_ptr<graph::GenericSubscription>> subscriptions_;
};

template <class T>
const T& input(const std::shared_ptr<const void>& m) {
  return *std::static_pointer_cast<const T>(m);
}

AprilTagParams apriltag_params(const KernelConfig& c) {
  const auto& p = c.parameters;
  AprilTagParams out;
  out.family = p.get_string("family");
  out.size = p.get_double("size");
  out.max_hamming = static_cast<int>(p.get_int("max_hamming"));
  out.decimate = p.get_double("decimate");
  out.blur = p.get_double("blur");
  out.threads = static_cast<int>(p.get_int("threads"));
  out.refine_edges = p.get_bool("refine_edges");
  out.sharpening = p.get_double("sharpening");
  try {
    validate(out);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("node '" + c.node_name + "': " + e.what());
  }
  return out;
}

class AprilTagNode final : public SyncedNode<2> {
 public:
  enum Input { kImage, kInfo };

  AprilTagNode(graph::Context& context, const KernelConfig& config)
      : SyncedNode(context, config, {"image", "camera_info"}), detector_(apriltag_params(config)) {
    detections_out_ =
        create_publisher<msgs::AprilTagDetectionArray>(config.topic("detections"), config.qos);
    poses_out_ = create_publisher<msgs::PoseArray>(config.topic("poses"), config.qos);
    subscribe<msgs::Image>(config, kImage);
    subscribe<msgs::CameraInfo>(config, kInfo);
  }

 private:
  void process(const MessageSync<2>::Set& set) override {
    const auto& image = input<msgs::Image>(set[kImage]);
    auto detections = std::make_shared<msgs::AprilTagDetectionArray>();
    auto poses = std::make_shared<msgs::PoseArray>();
    plugin::trace_kernel_init(*this, kKernel, image.header.stamp.to_ns(), image);
    detector_.detect(image, input<msgs::CameraInfo>(set[kInfo]), *detections, *poses);
    plugin::trace_kernel_fini(*this, kKernel, *detections);
    // Poses first: a subscriber pairing them with the detections finds them waiting.
    poses_out_->publish(std::shared_ptr<const msgs::PoseArray>(std::move(poses)));
    detections_out_->publish(
        std::shared_ptr<const msgs::AprilTagDetectionArray>(std::move(detections)));
  }

  static constexpr const char* kKernel = "apriltag/detect";
  AprilTagDetector detector_;
  std::shared_ptr<graph::Publisher<msgs::AprilTagDetectionArray>> detections_out_;
  std::shared_ptr<graph::Publisher<msgs::PoseArray>> poses_out_;
};

}  // namespace

void register_kernels(plugin::Registrar& registrar) {
  const AprilTagParams tag;
  registrar.add_kernel(
      {.name = "apriltag/detect",
       .description = "AprilTag detection (libapriltag) and each tag's pose from its corners and "
                      "size, as apriltag_ros",
       .inputs = {{"image", "sensor_msgs/msg/Image"},
                  {"camera_info", "sensor_msgs/msg/CameraInfo"}},
       .outputs = {{"detections", "apriltag_msgs/msg/AprilTagDetectionArray"},
                   {"poses", "geometry_msgs/msg/PoseArray"}},
       .parameters =
           {plugin::string_parameter("family", tag.family, "tag family: 16h5, 25h9 or 36h11"),
            plugin::double_parameter("size", tag.size, "edge of the black border square, m"),
            plugin::int_parameter("max_hamming", tag.max_hamming,
                                  "bits a detection may have corrected (0..2)"),
            plugin::double_parameter("decimate", tag.decimate,
                                     "find quads on the image decimated by this factor"),
            plugin::double_parameter("blur", tag.blur,
                                     "Gaussian sigma (px) before segmentation; < 0 sharpens"),
            plugin::int_parameter("threads", tag.threads, "libapriltag worker threads"),
            plugin::bool_parameter("refine_edges", tag.refine_edges,
                                   "snap quad edges to the image gradients"),
            plugin::double_parameter("sharpening", tag.sharpening, "decode sharpening")}},
      [](graph::Context& context, const KernelConfig& config) {
        return std::make_shared<AprilTagNode>(context, config);
      });
}

}  // namespace robotperf::localization
