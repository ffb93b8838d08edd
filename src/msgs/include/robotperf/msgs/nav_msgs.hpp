#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/msgs/builtin_interfaces.hpp"
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

// nav_msgs/MapMetaData: a grid's cell size (m), size in cells, and the pose of cell (0, 0)'s
// corner in the map frame.
struct MapMetaData {
  Time map_load_time;
  float resolution = 0;
  uint32_t width = 0;
  uint32_t height = 0;
  Pose origin;
  friend bool operator==(const MapMetaData&, const MapMetaData&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, MapMetaData>
void visit_fields(V& v, M& m) {
  v(m.map_load_time);
  v(m.resolution);
  v(m.width);
  v(m.height);
  v(m.origin);
}
template <>
struct MessageTraits<MapMetaData> {
  static constexpr std::string_view ros_type = "nav_msgs/msg/MapMetaData";
};

// nav_msgs/OccupancyGrid: row-major cells from (0, 0), each -1 unknown or 0..100 occupied
// probability in percent.
struct OccupancyGrid {
  Header header;
  MapMetaData info;
  std::vector<int8_t> data;
  friend bool operator==(const OccupancyGrid&, const OccupancyGrid&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, OccupancyGrid>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.info);
  v(m.data);
}
template <>
struct MessageTraits<OccupancyGrid> {
  static constexpr std::string_view ros_type = "nav_msgs/msg/OccupancyGrid";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<Odometry>();
extern template const TypeSupport& type_support<MapMetaData>();
extern template const TypeSupport& type_support<OccupancyGrid>();

}  // namespace robotperf::msgs
