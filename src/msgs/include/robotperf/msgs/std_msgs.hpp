#pragma once

#include <string>

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
// message ID in header.stamp (DESIGN.md §3.1).
template <class T>
concept Stamped = requires(T& m) {
  { m.header } -> std::convertible_to<Header&>;
};

}  // namespace robotperf::msgs
