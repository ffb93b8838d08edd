// geometry_msgs: the poses, motions and transforms that control and
// manipulation graphs exchange.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "robotperf/msgs/std_msgs.hpp"

namespace robotperf::msgs {

struct Vector3 {
  double x = 0;
  double y = 0;
  double z = 0;
  friend bool operator==(const Vector3&, const Vector3&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Vector3>
void visit_fields(V& v, M& m) {
  v(m.x);
  v(m.y);
  v(m.z);
}
template <>
struct MessageTraits<Vector3> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/Vector3";
};

struct Point {
  double x = 0;
  double y = 0;
  double z = 0;
  friend bool operator==(const Point&, const Point&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Point>
void visit_fields(V& v, M& m) {
  v(m.x);
  v(m.y);
  v(m.z);
}
template <>
struct MessageTraits<Point> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/Point";
};

// Defaults to the identity rotation, as the .msg does (w 1).
struct Quaternion {
  double x = 0;
  double y = 0;
  double z = 0;
  double w = 1;
  friend bool operator==(const Quaternion&, const Quaternion&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Quaternion>
void visit_fields(V& v, M& m) {
  v(m.x);
  v(m.y);
  v(m.z);
  v(m.w);
}
template <>
struct MessageTraits<Quaternion> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/Quaternion";
};

struct Pose {
  Point position;
  Quaternion orientation;
  friend bool operator==(const Pose&, const Pose&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Pose>
void visit_fields(V& v, M& m) {
  v(m.position);
  v(m.orientation);
}
template <>
struct MessageTraits<Pose> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/Pose";
};

struct PoseStamped {
  Header header;
  Pose pose;
  friend bool operator==(const PoseStamped&, const PoseStamped&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, PoseStamped>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.pose);
}
template <>
struct MessageTraits<PoseStamped> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/PoseStamped";
};

struct PoseArray {
  Header header;
  std::vector<Pose> poses;
  friend bool operator==(const PoseArray&, const PoseArray&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, PoseArray>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.poses);
}
template <>
struct MessageTraits<PoseArray> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/PoseArray";
};

// Row-major 6x6 covariance of (x, y, z, rotation about x, y, z).
using Covariance6 = std::array<double, 36>;

struct PoseWithCovariance {
  Pose pose;
  Covariance6 covariance{};
  friend bool operator==(const PoseWithCovariance&, const PoseWithCovariance&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, PoseWithCovariance>
void visit_fields(V& v, M& m) {
  v(m.pose);
  v(m.covariance);
}
template <>
struct MessageTraits<PoseWithCovariance> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/PoseWithCovariance";
};

struct PoseWithCovarianceStamped {
  Header header;
  PoseWithCovariance pose;
  friend bool operator==(const PoseWithCovarianceStamped&,
                         const PoseWithCovarianceStamped&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, PoseWithCovarianceStamped>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.pose);
}
template <>
struct MessageTraits<PoseWithCovarianceStamped> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/PoseWithCovarianceStamped";
};

struct Twist {
  Vector3 linear;
  Vector3 angular;
  friend bool operator==(const Twist&, const Twist&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Twist>
void visit_fields(V& v, M& m) {
  v(m.linear);
  v(m.angular);
}
template <>
struct MessageTraits<Twist> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/Twist";
};

struct TwistStamped {
  Header header;
  Twist twist;
  friend bool operator==(const TwistStamped&, const TwistStamped&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, TwistStamped>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.twist);
}
template <>
struct MessageTraits<TwistStamped> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/TwistStamped";
};

struct TwistWithCovariance {
  Twist twist;
  Covariance6 covariance{};
  friend bool operator==(const TwistWithCovariance&, const TwistWithCovariance&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, TwistWithCovariance>
void visit_fields(V& v, M& m) {
  v(m.twist);
  v(m.covariance);
}
template <>
struct MessageTraits<TwistWithCovariance> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/TwistWithCovariance";
};

struct Transform {
  Vector3 translation;
  Quaternion rotation;
  friend bool operator==(const Transform&, const Transform&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Transform>
void visit_fields(V& v, M& m) {
  v(m.translation);
  v(m.rotation);
}
template <>
struct MessageTraits<Transform> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/Transform";
};

struct TransformStamped {
  Header header;
  std::string child_frame_id;
  Transform transform;
  friend bool operator==(const TransformStamped&, const TransformStamped&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, TransformStamped>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.child_frame_id);
  v(m.transform);
}
template <>
struct MessageTraits<TransformStamped> {
  static constexpr std::string_view ros_type = "geometry_msgs/msg/TransformStamped";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<Vector3>();
extern template const TypeSupport& type_support<Point>();
extern template const TypeSupport& type_support<Quaternion>();
extern template const TypeSupport& type_support<Pose>();
extern template const TypeSupport& type_support<PoseStamped>();
extern template const TypeSupport& type_support<PoseArray>();
extern template const TypeSupport& type_support<PoseWithCovariance>();
extern template const TypeSupport& type_support<PoseWithCovarianceStamped>();
extern template const TypeSupport& type_support<Twist>();
extern template const TypeSupport& type_support<TwistStamped>();
extern template const TypeSupport& type_support<TwistWithCovariance>();
extern template const TypeSupport& type_support<Transform>();
extern template const TypeSupport& type_support<TransformStamped>();

}  // namespace robotperf::msgs
