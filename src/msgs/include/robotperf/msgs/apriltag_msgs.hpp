#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/msgs/std_msgs.hpp"

namespace robotperf::msgs {

// apriltag_msgs (christianrauch/apriltag_msgs, as apriltag_ros for ROS 2 publishes): the
// detected tags of one image, in pixel coordinates.
struct AprilTagPoint {
  double x = 0;
  double y = 0;
  friend bool operator==(const AprilTagPoint&, const AprilTagPoint&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, AprilTagPoint>
void visit_fields(V& v, M& m) {
  v(m.x);
  v(m.y);
}
template <>
struct MessageTraits<AprilTagPoint> {
  static constexpr std::string_view ros_type = "apriltag_msgs/msg/Point";
};

struct AprilTagDetection {
  std::string family;  // "36h11"
  int32_t id = 0;
  int32_t hamming = 0;  // bits corrected
  float goodness = 0;
  float decision_margin = 0;
  AprilTagPoint centre;
  // The tag's corners in the image, in libapriltag's order (counter-clockwise in the tag's own
  // frame, starting at (-1, 1)).
  std::array<AprilTagPoint, 4> corners{};
  std::array<double, 9> homography{};  // row-major, tag (-1..1) -> pixels
  friend bool operator==(const AprilTagDetection&, const AprilTagDetection&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, AprilTagDetection>
void visit_fields(V& v, M& m) {
  v(m.family);
  v(m.id);
  v(m.hamming);
  v(m.goodness);
  v(m.decision_margin);
  v(m.centre);
  v(m.corners);
  v(m.homography);
}
template <>
struct MessageTraits<AprilTagDetection> {
  static constexpr std::string_view ros_type = "apriltag_msgs/msg/AprilTagDetection";
};

struct AprilTagDetectionArray {
  Header header;
  std::vector<AprilTagDetection> detections;
  friend bool operator==(const AprilTagDetectionArray&, const AprilTagDetectionArray&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, AprilTagDetectionArray>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.detections);
}
template <>
struct MessageTraits<AprilTagDetectionArray> {
  static constexpr std::string_view ros_type = "apriltag_msgs/msg/AprilTagDetectionArray";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<AprilTagPoint>();
extern template const TypeSupport& type_support<AprilTagDetection>();
extern template const TypeSupport& type_support<AprilTagDetectionArray>();

}  // namespace robotperf::msgs
