#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/msgs/std_msgs.hpp"

namespace robotperf::msgs {

struct RegionOfInterest {
  uint32_t x_offset = 0;
  uint32_t y_offset = 0;
  uint32_t height = 0;
  uint32_t width = 0;
  bool do_rectify = false;
  friend bool operator==(const RegionOfInterest&, const RegionOfInterest&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, RegionOfInterest>
void visit_fields(V& v, M& m) {
  v(m.x_offset);
  v(m.y_offset);
  v(m.height);
  v(m.width);
  v(m.do_rectify);
}

struct CameraInfo {
  Header header;
  uint32_t height = 0;
  uint32_t width = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{};
  std::array<double, 9> r{};
  std::array<double, 12> p{};
  uint32_t binning_x = 0;
  uint32_t binning_y = 0;
  RegionOfInterest roi;
  friend bool operator==(const CameraInfo&, const CameraInfo&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, CameraInfo>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.height);
  v(m.width);
  v(m.distortion_model);
  v(m.d);
  v(m.k);
  v(m.r);
  v(m.p);
  v(m.binning_x);
  v(m.binning_y);
  v(m.roi);
}

struct Image {
  Header header;
  uint32_t height = 0;
  uint32_t width = 0;
  std::string encoding;
  uint8_t is_bigendian = 0;
  uint32_t step = 0;
  std::vector<uint8_t> data;
  friend bool operator==(const Image&, const Image&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Image>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.height);
  v(m.width);
  v(m.encoding);
  v(m.is_bigendian);
  v(m.step);
  v(m.data);
}

struct PointField {
  // datatype values.
  static constexpr uint8_t kInt8 = 1;
  static constexpr uint8_t kUint8 = 2;
  static constexpr uint8_t kInt16 = 3;
  static constexpr uint8_t kUint16 = 4;
  static constexpr uint8_t kInt32 = 5;
  static constexpr uint8_t kUint32 = 6;
  static constexpr uint8_t kFloat32 = 7;
  static constexpr uint8_t kFloat64 = 8;

  std::string name;
  uint32_t offset = 0;
  uint8_t datatype = 0;
  uint32_t count = 0;
  friend bool operator==(const PointField&, const PointField&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, PointField>
void visit_fields(V& v, M& m) {
  v(m.name);
  v(m.offset);
  v(m.datatype);
  v(m.count);
}

struct PointCloud2 {
  Header header;
  uint32_t height = 0;
  uint32_t width = 0;
  std::vector<PointField> fields;
  bool is_bigendian = false;
  uint32_t point_step = 0;
  uint32_t row_step = 0;
  std::vector<uint8_t> data;
  bool is_dense = false;
  friend bool operator==(const PointCloud2&, const PointCloud2&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, PointCloud2>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.height);
  v(m.width);
  v(m.fields);
  v(m.is_bigendian);
  v(m.point_step);
  v(m.row_step);
  v(m.data);
  v(m.is_dense);
}

template <>
struct MessageTraits<RegionOfInterest> {
  static constexpr std::string_view ros_type = "sensor_msgs/msg/RegionOfInterest";
};
template <>
struct MessageTraits<CameraInfo> {
  static constexpr std::string_view ros_type = "sensor_msgs/msg/CameraInfo";
};
template <>
struct MessageTraits<Image> {
  static constexpr std::string_view ros_type = "sensor_msgs/msg/Image";
};
template <>
struct MessageTraits<PointField> {
  static constexpr std::string_view ros_type = "sensor_msgs/msg/PointField";
};
template <>
struct MessageTraits<PointCloud2> {
  static constexpr std::string_view ros_type = "sensor_msgs/msg/PointCloud2";
};

// sensor_msgs/JointState: per named joint, any of position, velocity and
// effort (each empty or as long as name).
struct JointState {
  Header header;
  std::vector<std::string> name;
  std::vector<double> position;
  std::vector<double> velocity;
  std::vector<double> effort;
  friend bool operator==(const JointState&, const JointState&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, JointState>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.name);
  v(m.position);
  v(m.velocity);
  v(m.effort);
}
template <>
struct MessageTraits<JointState> {
  static constexpr std::string_view ros_type = "sensor_msgs/msg/JointState";
};

// sensor_msgs/LaserScan: one sweep of a planar range finder; beam i at angle_min + i *
// angle_increment about +z from +x; a range outside [range_min, range_max] is no return.
struct LaserScan {
  Header header;
  float angle_min = 0;
  float angle_max = 0;
  float angle_increment = 0;
  float time_increment = 0;
  float scan_time = 0;
  float range_min = 0;
  float range_max = 0;
  std::vector<float> ranges;
  std::vector<float> intensities;
  friend bool operator==(const LaserScan&, const LaserScan&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, LaserScan>
void visit_fields(V& v, M& m) {
  v(m.header);
  v(m.angle_min);
  v(m.angle_max);
  v(m.angle_increment);
  v(m.time_increment);
  v(m.scan_time);
  v(m.range_min);
  v(m.range_max);
  v(m.ranges);
  v(m.intensities);
}
template <>
struct MessageTraits<LaserScan> {
  static constexpr std::string_view ros_type = "sensor_msgs/msg/LaserScan";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<RegionOfInterest>();
extern template const TypeSupport& type_support<CameraInfo>();
extern template const TypeSupport& type_support<Image>();
extern template const TypeSupport& type_support<PointField>();
extern template const TypeSupport& type_support<PointCloud2>();
extern template const TypeSupport& type_support<JointState>();
extern template const TypeSupport& type_support<LaserScan>();

}  // namespace robotperf::msgs
