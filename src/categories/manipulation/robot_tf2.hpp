// The arm's frames through tf2, for the manipulation kernels' use_tf2 mode (RobotPerf's m2-m7:
// d1-d6 with their transforms going through geometry2). A node in that mode does
// robot_state_publisher's part: each joint state it handles becomes its links' transforms to their
// parents, set into the node's tf2 buffer at the message's stamp and broadcast on /tf, and the
// arm's fixed mount (world -> base link) is set and broadcast once on /tf_static. And it does a tf2
// listener's part: the frame relations its answer needs are looked up in that buffer
// (docs/benchmarks/meta.md says which for each kernel).
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "robotperf/manipulation/robot_model.hpp"
#include "robotperf/plugin.hpp"

namespace robotperf::manipulation {

struct Tf2Settings {
  bool use_tf2 = false;
  std::string world_frame;
};
// Declared by every manipulation kernel.
extern const plugin::ParameterStruct<Tf2Settings> kTf2Parameters;
// `parameters` and the tf2 ones.
std::vector<plugin::ParameterInfo> with_tf2(std::vector<plugin::ParameterInfo> parameters);
// The tf2 output ports every manipulation kernel has (wired or not: /tf and /tf_static).
std::vector<plugin::PortInfo> with_tf2_ports(std::vector<plugin::PortInfo> outputs);

class RobotTf2 {
 public:
  // Sets and broadcasts the mount. Throws std::invalid_argument for an empty world frame or one
  // named as a link of the arm.
  RobotTf2(graph::Node& node, const plugin::KernelConfig& config, const RobotModel& model,
           const std::string& world_frame);

  // The links' transforms of joint state `q` (model order) at `stamp_ns`: into the buffer, and
  // on /tf. Throws std::invalid_argument for a stamp the buffer has (or one older than its cache):
  // tf2 would keep the state it has.
  void set_state(const double* q, int64_t stamp_ns);
  // `source`'s pose in `target` at `stamp_ns`. Throws std::invalid_argument with tf2's text when
  // the buffer cannot answer (an unknown frame, a time it has no state for).
  Eigen::Isometry3d lookup(const std::string& target, const std::string& source,
                           int64_t stamp_ns) const;
  // Every link's pose in the base frame at `stamp_ns` (model.links() order): one lookup each.
  void link_poses(int64_t stamp_ns, std::vector<Eigen::Isometry3d>& poses) const;

 private:
  const RobotModel& model_;
  plugin::TransformBuffer buffer_;
  plugin::TransformBroadcaster broadcaster_;
  plugin::StaticTransformBroadcaster static_broadcaster_;
  std::vector<Eigen::Isometry3d> poses_;  // set_state's scratch
};

}  // namespace robotperf::manipulation
