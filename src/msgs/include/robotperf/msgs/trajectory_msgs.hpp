// trajectory_msgs and control_msgs: joint trajectories and the state a
// trajectory controller reports.
#pragma once

#include <string>
#include <vector>

#include "robotperf/msgs/geometry_msgs.hpp"

namespace robotperf::msgs {

struct JointTrajectoryPoint {
  std::vector<double> positions;
  std::vector<double> velocities;
  std::vector<double> accelerations;
  std::vector<double> effort;
  Duration time_from_start;
  friend bool operator==(const JointTrajectoryPoint&, const JointTrajectoryPoint&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, JointTrajectoryPoint>
void visit_fields(V& v, M& m) {
  v(m.positions);
  v(m.velocities);
  v(m.accelerations);
  v(m.effort);
  v(m.time_from_start);
}
template <>
struct MessageTraits<JointTrajectoryPoint> {
  static constexpr std::string_view ros_type = "trajectory_msgs/msg/JointTrajectoryPoint";
};

struct JointTrajectory {
  Header header;
  std::vector<std::string> joint_names;
  std::vector<JointTrajectoryPoint> points;
  friend bool operator==(const JointTrajectory&, const JointTrajectory&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, JointTrajectory>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.joint_names);
  v(m.points);
}
template <>
struct MessageTraits<JointTrajectory> {
  static constexpr std::string_view ros_type = "trajectory_msgs/msg/JointTrajectory";
};

struct MultiDOFJointTrajectoryPoint {
  std::vector<Transform> transforms;
  std::vector<Twist> velocities;
  std::vector<Twist> accelerations;
  Duration time_from_start;
  friend bool operator==(const MultiDOFJointTrajectoryPoint&,
                         const MultiDOFJointTrajectoryPoint&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, MultiDOFJointTrajectoryPoint>
void visit_fields(V& v, M& m) {
  v(m.transforms);
  v(m.velocities);
  v(m.accelerations);
  v(m.time_from_start);
}
template <>
struct MessageTraits<MultiDOFJointTrajectoryPoint> {
  static constexpr std::string_view ros_type = "trajectory_msgs/msg/MultiDOFJointTrajectoryPoint";
};

// control_msgs/JointTrajectoryControllerState (current control_msgs layout):
// reference = sampled desired state, feedback = measured, error = reference -
// feedback, output = what was commanded.
struct JointTrajectoryControllerState {
  Header header;
  std::vector<std::string> joint_names;
  JointTrajectoryPoint reference;
  JointTrajectoryPoint feedback;
  JointTrajectoryPoint error;
  JointTrajectoryPoint output;
  std::vector<std::string> multi_dof_joint_names;
  MultiDOFJointTrajectoryPoint multi_dof_reference;
  MultiDOFJointTrajectoryPoint multi_dof_feedback;
  MultiDOFJointTrajectoryPoint multi_dof_error;
  MultiDOFJointTrajectoryPoint multi_dof_output;
  double speed_scaling_factor = 1.0;
  friend bool operator==(const JointTrajectoryControllerState&,
                         const JointTrajectoryControllerState&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, JointTrajectoryControllerState>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.joint_names);
  v(m.reference);
  v(m.feedback);
  v(m.error);
  v(m.output);
  v(m.multi_dof_joint_names);
  v(m.multi_dof_reference);
  v(m.multi_dof_feedback);
  v(m.multi_dof_error);
  v(m.multi_dof_output);
  v(m.speed_scaling_factor);
}
template <>
struct MessageTraits<JointTrajectoryControllerState> {
  static constexpr std::string_view ros_type = "control_msgs/msg/JointTrajectoryControllerState";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<JointTrajectoryPoint>();
extern template const TypeSupport& type_support<JointTrajectory>();
extern template const TypeSupport& type_support<MultiDOFJointTrajectoryPoint>();
extern template const TypeSupport& type_support<JointTrajectoryControllerState>();

}  // namespace robotperf::msgs
