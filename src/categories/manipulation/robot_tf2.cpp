#include "robot_tf2.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "robotperf/msgs/eigen_geometry.hpp"

namespace robotperf::manipulation {

const plugin::ParameterStruct<Tf2Settings> kTf2Parameters{
    plugin::field(&Tf2Settings::use_tf2, "use_tf2", false,
                  "the arm's frames go through a tf2 buffer: its joint states set as link "
                  "transforms (and broadcast on /tf), the answer's frame relations looked up "
                  "(RobotPerf m2-m7)"),
    plugin::field(
        &Tf2Settings::world_frame, "world_frame", std::string("world"),
        "with use_tf2: the frame the arm's base is mounted in (identity, on /tf_static)")};

std::vector<plugin::ParameterInfo> with_tf2(std::vector<plugin::ParameterInfo> parameters) {
  for (auto& p : kTf2Parameters.declarations()) parameters.push_back(std::move(p));
  return parameters;
}

std::vector<plugin::PortInfo> with_tf2_ports(std::vector<plugin::PortInfo> outputs) {
  outputs.push_back({"tf", "tf2_msgs/msg/TFMessage"});
  outputs.push_back({"tf_static", "tf2_msgs/msg/TFMessage"});
  return outputs;
}

namespace {

// The port's topic, else tf2's standard one.
std::string topic_or(const plugin::KernelConfig& config, const std::string& port,
                     const std::string& standard) {
  return config.topics.contains(port) ? config.topic(port) : standard;
}

}  // namespace

RobotTf2::RobotTf2(graph::Node& node, const plugin::KernelConfig& config, const RobotModel& model,
                   const std::string& world_frame)
    : model_(model),
      buffer_(config.node_name),
      broadcaster_(node, topic_or(config, "tf", "/tf")),
      static_broadcaster_(node, topic_or(config, "tf_static", "/tf_static")) {
  const auto& links = model.links();
  auto is_link = [&](const std::string& name) {
    return std::ranges::any_of(links, [&](const Link& l) { return l.name == name; });
  };
  if (world_frame.empty() || is_link(world_frame)) {
    throw std::invalid_argument("node '" + config.node_name + "': world_frame '" + world_frame +
                                "' must be a name that is not a link of the arm");
  }
  // The tip is looked up as a frame of its own: it must be one of the links the state moves.
  if (!is_link(model.tip_link()))
    throw std::invalid_argument("the arm's tip '" + model.tip_link() + "' is not one of its links");
  msgs::TransformStamped mount;
  mount.header.frame_id = world_frame;
  mount.child_frame_id = model.base_link();
  mount.transform.rotation.w = 1;
  buffer_.set_transform(mount, config.node_name, true);
  static_broadcaster_.send({mount});
}

void RobotTf2::set_state(const double* q, int64_t stamp_ns) {
  model_.link_poses(q, poses_);
  const auto& links = model_.links();
  std::vector<msgs::TransformStamped> transforms;
  transforms.reserve(links.size() - 1);
  const msgs::Time stamp = msgs::Time::from_ns(stamp_ns);
  for (std::size_t i = 1; i < links.size(); ++i) {
    msgs::TransformStamped t;
    t.header.stamp = stamp;
    t.header.frame_id = links[i - 1].name;
    t.child_frame_id = links[i].name;
    t.transform = msgs::transform_msg_of(poses_[i - 1].inverse() * poses_[i]);
    // Refused when the buffer has the stamp (or it is older than the cache): a lookup at it would
    // answer with another state.
    if (!buffer_.set_transform(t, buffer_.owner(), false)) {
      throw std::invalid_argument("the tf2 buffer already has a state at stamp " +
                                  std::to_string(stamp_ns) + " ns, or the stamp is too old");
    }
    transforms.push_back(std::move(t));
  }
  broadcaster_.send(std::move(transforms));
}

Eigen::Isometry3d RobotTf2::lookup(const std::string& target, const std::string& source,
                                   int64_t stamp_ns) const {
  try {
    return msgs::isometry_of(buffer_.lookup_transform(target, source, stamp_ns).transform);
  } catch (const plugin::TransformError& e) {
    throw std::invalid_argument(e.what());
  }
}

void RobotTf2::link_poses(int64_t stamp_ns, std::vector<Eigen::Isometry3d>& poses) const {
  const auto& links = model_.links();
  poses.assign(links.size(), Eigen::Isometry3d::Identity());  // the base link's own pose
  for (std::size_t i = 1; i < links.size(); ++i)
    poses[i] = lookup(model_.base_link(), links[i].name, stamp_ns);
}

}  // namespace robotperf::manipulation
