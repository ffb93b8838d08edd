// The turtle tf2 demo's nodes (geometry2's turtle_tf2_broadcaster and turtle_tf2_listener): a
// broadcaster turns each pose of its turtle into world -> turtle on /tf; the listener keeps /tf
// and /tf_static in a tf2 buffer and, once both turtles' transforms of a time are in, looks up the
// leader in the follower's frame and publishes the follow command with that time.
#include <cmath>
#include <stdexcept>
#include <string>

#include "category.hpp"
#include "robotperf/msgs/geometry_msgs.hpp"
#include "robotperf/msgs/tf2_msgs.hpp"

namespace robotperf::meta {
namespace {

using plugin::KernelConfig;

struct BroadcasterSettings {
  std::string child_frame;
};
const plugin::ParameterStruct<BroadcasterSettings> kBroadcasterParameters{
    plugin::field(&BroadcasterSettings::child_frame, "child_frame", std::string("turtle1"),
                  "the turtle's frame; its parent is the pose's header.frame_id")};

class Tf2BroadcasterNode final : public graph::Node, public plugin::NodeCounters {
 public:
  Tf2BroadcasterNode(graph::Context& context, const KernelConfig& config)
      : graph::Node(context, config.node_name),
        child_frame_(kBroadcasterParameters.read(config.parameters).child_frame),
        broadcaster_(*this, config.topic("tf")) {
    if (child_frame_.empty())
      throw std::invalid_argument("node '" + config.node_name + "': child_frame is empty");
    input_ = create_subscription<msgs::PoseStamped>(
        config.topic("pose"), config.qos, [this](std::shared_ptr<const msgs::PoseStamped> pose) {
          const auto& p = pose->pose;
          if (pose->header.frame_id.empty() || !std::isfinite(p.position.x) ||
              !std::isfinite(p.position.y) || !std::isfinite(p.position.z)) {
            skipped_.note(name(), "a pose without a frame or with a position that is not finite");
            return;
          }
          msgs::TransformStamped t;
          t.header = pose->header;
          t.child_frame_id = child_frame_;
          t.transform.translation = {p.position.x, p.position.y, p.position.z};
          t.transform.rotation = p.orientation;
          broadcaster_.send({std::move(t)});
          ++sent_;
        });
  }
  std::map<std::string, uint64_t> counters() const override {
    return {{"transforms_sent", sent_}, {"poses_skipped", skipped_.count()}};
  }

 private:
  std::string child_frame_;
  plugin::TransformBroadcaster broadcaster_;
  std::shared_ptr<graph::GenericSubscription> input_;
  uint64_t sent_ = 0;
  plugin::SkippedInputs skipped_{"pose"};
};

struct ListenerSettings {
  std::string follower_frame;
  std::string leader_frame;
};
const plugin::ParameterStruct<ListenerSettings> kListenerParameters{
    plugin::field(&ListenerSettings::follower_frame, "follower_frame", std::string("turtle2"),
                  "the turtle that follows: the command is for it, in its frame"),
    plugin::field(&ListenerSettings::leader_frame, "leader_frame", std::string("turtle1"),
                  "the turtle followed (turtle_tf2_listener's target_frame)")};

class TurtleTf2ListenerNode final : public graph::Node, public plugin::NodeCounters {
 public:
  TurtleTf2ListenerNode(graph::Context& context, const KernelConfig& config)
      : graph::Node(context, config.node_name),
        settings_(kListenerParameters.read(config.parameters)),
        buffer_(config.node_name) {
    if (settings_.follower_frame.empty() || settings_.leader_frame.empty() ||
        settings_.follower_frame == settings_.leader_frame)
      throw std::invalid_argument("node '" + config.node_name +
                                  "': follower_frame and leader_frame must be two frames");
    command_ = create_publisher<msgs::TwistStamped>(config.topic("cmd_vel"), config.qos);
    listener_ = std::make_unique<plugin::TransformListener>(
        *this, buffer_, [this](const msgs::TFMessage& m) { follow(m); }, config.topic("tf"));
  }
  std::map<std::string, uint64_t> counters() const override {
    return {{"commands", commands_}, {"transforms_refused", listener_->refused()}};
  }

 private:
  // For each time the message brings that is newer than the last answered one: the command, as
  // soon as the buffer holds both turtles at that time (the other turtle's transform of a frame
  // may come first or second).
  void follow(const msgs::TFMessage& message) {
    for (const auto& t : message.transforms) {
      const int64_t time = t.header.stamp.to_ns();
      if (time <= answered_ ||
          !buffer_.can_transform(settings_.follower_frame, settings_.leader_frame, time))
        continue;
      const bool traced = plugin::kernel_trace_enabled();
      if (traced) plugin::trace_kernel_init(name().c_str(), "turtle_tf2_listener", time, 0);
      const msgs::TransformStamped leader =
          buffer_.lookup_transform(settings_.follower_frame, settings_.leader_frame, time);
      auto command = std::make_shared<msgs::TwistStamped>();
      command->header.stamp = leader.header.stamp;
      command->header.frame_id = settings_.follower_frame;
      command->twist =
          follow_command(leader.transform.translation.x, leader.transform.translation.y);
      if (traced) plugin::trace_kernel_fini(*this, "turtle_tf2_listener", *command);
      command_->publish(std::shared_ptr<const msgs::TwistStamped>(std::move(command)));
      answered_ = time;
      ++commands_;
    }
  }

  ListenerSettings settings_;
  plugin::TransformBuffer buffer_;
  std::shared_ptr<graph::Publisher<msgs::TwistStamped>> command_;
  std::unique_ptr<plugin::TransformListener> listener_;
  int64_t answered_ = INT64_MIN;
  uint64_t commands_ = 0;
};

template <class Node>
plugin::KernelFactory factory() {
  return [](graph::Context& context, const KernelConfig& config) {
    return std::make_shared<Node>(context, config);
  };
}

}  // namespace

void register_kernels(plugin::Registrar& registrar) {
  const plugin::PortInfo tf{"tf", "tf2_msgs/msg/TFMessage"};
  registrar.add_kernel({.name = "meta/tf2_broadcaster",
                        .description = "world -> turtle on /tf from each pose of the turtle "
                                       "(turtle_tf2_broadcaster; tf2_ros's QoS)",
                        .inputs = {{"pose", "geometry_msgs/msg/PoseStamped"}},
                        .outputs = {tf},
                        .parameters = kBroadcasterParameters.declarations()},
                       factory<Tf2BroadcasterNode>());
  registrar.add_kernel(
      {.name = "meta/turtle_tf2_listener",
       .description = "/tf and /tf_static into a tf2 buffer; the leader looked up in the "
                      "follower's frame at each time both are in, and the follow command "
                      "(turtle_tf2_listener)",
       .inputs = {tf},
       .outputs = {{"cmd_vel", "geometry_msgs/msg/TwistStamped"}},
       .parameters = kListenerParameters.declarations()},
      factory<TurtleTf2ListenerNode>());
}

}  // namespace robotperf::meta
