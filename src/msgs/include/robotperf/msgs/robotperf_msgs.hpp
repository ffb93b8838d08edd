// robotperf_msgs: the results of the manipulation kernels where no ROS 2 message fits (ROS
// answers these through services and actions). Plain messages with a std_msgs/Header, so that
// the Playback's message ID travels through them like any other output.
#pragma once

#include <string>

#include "robotperf/msgs/trajectory_msgs.hpp"

namespace robotperf::msgs {

// The answer to one boolean collision query (a JointState of the arm).
struct CollisionResult {
  Header header;
  bool in_collision = false;
  bool with_scene = false;  // the contact reported is robot vs scene, else robot vs itself
  std::string first;        // the two bodies of the contact reported ("" when none)
  std::string second;
  friend bool operator==(const CollisionResult&, const CollisionResult&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, CollisionResult>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.in_collision);
  v(m.with_scene);
  v(m.first);
  v(m.second);
}
template <>
struct MessageTraits<CollisionResult> {
  static constexpr std::string_view ros_type = "robotperf_msgs/msg/CollisionResult";
};

// A planning query answered and executed: the time-parameterised trajectory and how the
// simulated arm followed it.
struct PlanExecutionResult {
  Header header;
  bool success = false;
  double planning_time = 0;       // s, planner and simplification (0 from the built-in executor)
  JointTrajectory trajectory;     // empty when planning failed
  double path_length = 0;         // rad, joint space
  uint32_t execution_steps = 0;   // JointStates published while executing
  double max_tracking_error = 0;  // rad
  double final_error = 0;         // rad
  friend bool operator==(const PlanExecutionResult&, const PlanExecutionResult&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, PlanExecutionResult>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.success);
  v(m.planning_time);
  v(m.trajectory);
  v(m.path_length);
  v(m.execution_steps);
  v(m.max_tracking_error);
  v(m.final_error);
}
template <>
struct MessageTraits<PlanExecutionResult> {
  static constexpr std::string_view ros_type = "robotperf_msgs/msg/PlanExecutionResult";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<CollisionResult>();
extern template const TypeSupport& type_support<PlanExecutionResult>();

}  // namespace robotperf::msgs
