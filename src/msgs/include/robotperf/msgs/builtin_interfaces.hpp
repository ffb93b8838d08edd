#pragma once

#include <cstdint>

#include "robotperf/msgs/type_support.hpp"

namespace robotperf::msgs {

struct Time {
  int32_t sec = 0;
  uint32_t nanosec = 0;

  // The stamp as nanoseconds since its epoch.
  int64_t to_ns() const { return int64_t{sec} * 1'000'000'000 + nanosec; }
  // Floor division, so that nanosec stays in [0, 1e9) for stamps before the
  // epoch too (-1 ns is sec -1, nanosec 999999999), as rclcpp does.
  static Time from_ns(int64_t ns) {
    int64_t sec = ns / 1'000'000'000;
    int64_t nsec = ns % 1'000'000'000;
    if (nsec < 0) {
      sec -= 1;
      nsec += 1'000'000'000;
    }
    return Time{static_cast<int32_t>(sec), static_cast<uint32_t>(nsec)};
  }
  friend bool operator==(const Time&, const Time&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Time>
void visit_fields(V& v, M& m) {
  v(m.sec);
  v(m.nanosec);
}

struct Duration {
  int32_t sec = 0;
  uint32_t nanosec = 0;
  friend bool operator==(const Duration&, const Duration&) = default;
};
template <class V, class M>
requires std::is_same_v<std::remove_const_t<M>, Duration>
void visit_fields(V& v, M& m) {
  v(m.sec);
  v(m.nanosec);
}

template <>
struct MessageTraits<Time> {
  static constexpr std::string_view ros_type = "builtin_interfaces/msg/Time";
};
template <>
struct MessageTraits<Duration> {
  static constexpr std::string_view ros_type = "builtin_interfaces/msg/Duration";
};

// Their type supports live in the msgs library (type_support_instances.cpp).
extern template const TypeSupport& type_support<Time>();
extern template const TypeSupport& type_support<Duration>();

}  // namespace robotperf::msgs
