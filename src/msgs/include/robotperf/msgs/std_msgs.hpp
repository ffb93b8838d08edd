#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "robotperf/msgs/builtin_interfaces.hpp"

namespace robotperf::msgs {

struct Header {
  Time stamp;
  std::string frame_id;
  friend bool operator==(const Header&, const Header&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Header>
void visit_fields(V& v, M& m) {
  v(m.stamp);
  v(m.frame_id);
}
template <>
struct MessageTraits<Header> {
  static constexpr std::string_view ros_type = "std_msgs/msg/Header";
};

// Messages whose first field is a std_msgs/Header: the harness carries the
// message ID in header.stamp (docs/design.md §3.1).
template <class T>
concept Stamped = requires(T& m) {
  { m.header } -> std::convertible_to<Header&>;
};

struct MultiArrayDimension {
  std::string label;
  uint32_t size = 0;
  uint32_t stride = 0;
  friend bool operator==(const MultiArrayDimension&, const MultiArrayDimension&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, MultiArrayDimension>
void visit_fields(V& v, M& m) {
  v(m.label);
  v(m.size);
  v(m.stride);
}
template <>
struct MessageTraits<MultiArrayDimension> {
  static constexpr std::string_view ros_type = "std_msgs/msg/MultiArrayDimension";
};

struct MultiArrayLayout {
  std::vector<MultiArrayDimension> dim;
  uint32_t data_offset = 0;
  friend bool operator==(const MultiArrayLayout&, const MultiArrayLayout&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, MultiArrayLayout>
void visit_fields(V& v, M& m) {
  v(m.dim);
  v(m.data_offset);
}
template <>
struct MessageTraits<MultiArrayLayout> {
  static constexpr std::string_view ros_type = "std_msgs/msg/MultiArrayLayout";
};

// std_msgs/Float64MultiArray: the command message of forward command
// controllers (one value per joint, layout usually empty).
struct Float64MultiArray {
  MultiArrayLayout layout;
  std::vector<double> data;
  friend bool operator==(const Float64MultiArray&, const Float64MultiArray&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Float64MultiArray>
void visit_fields(V& v, M& m) {
  v(m.layout);
  v(m.data);
}
// Float64MultiArray has no header, so the harness carries a command's message ID (docs/design.md
// §3.1) in the label of the first layout dimension: "robotperf_id=<nanoseconds>". The dimension
// describes the data as a plain vector (size = stride = data.size()), so the layout stays true;
// forward command controllers read only `data`, as ros2_controllers' do.
inline constexpr std::string_view kMessageIdLabel = "robotperf_id=";
template <>
struct MessageTraits<Float64MultiArray> {
  static constexpr std::string_view ros_type = "std_msgs/msg/Float64MultiArray";
  // -1 when the message carries no ID.
  static int64_t id_ns(const Float64MultiArray& m) {
    if (m.layout.dim.empty()) return -1;
    const std::string& label = m.layout.dim.front().label;
    if (label.size() <= kMessageIdLabel.size() ||
        label.compare(0, kMessageIdLabel.size(), kMessageIdLabel) != 0)
      return -1;
    int64_t value = 0;
    for (std::size_t i = kMessageIdLabel.size(); i < label.size(); ++i) {
      const char c = label[i];
      if (c < '0' || c > '9' || value > (INT64_MAX - 9) / 10) return -1;
      value = value * 10 + (c - '0');
    }
    return value;
  }
  static void set_id_ns(Float64MultiArray& m, int64_t ns) {
    const auto n = static_cast<uint32_t>(m.data.size());
    if (m.layout.dim.empty()) m.layout.dim.push_back({"", n, n});
    m.layout.dim.front().label = std::string(kMessageIdLabel) + std::to_string(ns);
  }
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<Header>();
extern template const TypeSupport& type_support<MultiArrayDimension>();
extern template const TypeSupport& type_support<MultiArrayLayout>();
extern template const TypeSupport& type_support<Float64MultiArray>();

}  // namespace robotperf::msgs
