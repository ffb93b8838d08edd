#pragma once

#include <string>

#include "robotperf/msgs/geometry_msgs.hpp"

namespace robotperf::msgs {

// nav_msgs/Odometry: pose in header.frame_id, twist in child_frame_id.
struct Odometry {
  Header header;
  std::string child_frame_id;
  PoseWithCovariance pose;
  TwistWithCovariance twist;
  friend bool operator==(const Odometry&, const Odometry&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Odometry>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.child_frame_id);
  v(m.pose);
  v(m.twist);
}
template <>
struct MessageTraits<Odometry> {
  static constexpr std::string_view ros_type = "nav_msgs/msg/Odometry";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<Odometry>();

}  // namespace robotperf::msgs
